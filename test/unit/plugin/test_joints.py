"""Joint targets -> ActuatorCmd (NaN/inf rejected), ActuatorState -> JointStateView. No ROS."""

import math
import threading

import pytest
from rm_base.plugin import JointStateView, JointTarget, Mode, TargetRejectedError
from rm_base.plugin import build_actuator_cmd as build
from rm_base.plugin.joints import oldest_stamp

from rm_msgs.msg import ActuatorCmd, ActuatorState


def test_modes_match_the_message_constants():
    assert [int(m) for m in Mode] == [
        ActuatorCmd.MODE_OFF, ActuatorCmd.MODE_EFFORT, ActuatorCmd.MODE_VELOCITY,
        ActuatorCmd.MODE_POSITION, ActuatorCmd.MODE_MIT,
    ]


def test_targets_become_one_message_with_parallel_arrays():
    msg = build({
        'lf_wheel': JointTarget.with_velocity(3.0),
        'yaw': JointTarget.with_mit(0.5, 0.1, 0.2, kp=20.0, kd=1.5),
        'trigger': JointTarget.off(),
    })
    assert list(msg.name) == ['lf_wheel', 'yaw', 'trigger']
    assert list(msg.mode) == [ActuatorCmd.MODE_VELOCITY, ActuatorCmd.MODE_MIT, ActuatorCmd.MODE_OFF]
    assert list(msg.position) == [0.0, 0.5, 0.0]
    assert list(msg.velocity) == [3.0, 0.1, 0.0]
    assert list(msg.effort) == [0.0, 0.2, 0.0]
    assert list(msg.kp) == [0.0, 20.0, 0.0]
    assert list(msg.kd) == [0.0, 1.5, 0.0]


@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize('field', ['position', 'velocity', 'effort', 'kp', 'kd'])
def test_when_a_field_is_not_finite_expect_rejected(field, bad):
    target = JointTarget(Mode.MIT, **{field: bad})
    with pytest.raises(TargetRejectedError, match=f"joint 'yaw': {field} is not a finite"):
        build({'ok': JointTarget.with_velocity(1.0), 'yaw': target})


def test_when_a_field_is_not_a_number_expect_rejected():
    target = JointTarget(Mode.EFFORT, effort='strong')
    with pytest.raises(TargetRejectedError, match="joint 'yaw': effort must be a number"):
        build({'yaw': target})


@pytest.mark.parametrize('mode', [9, 'velocity', [2]])
def test_when_mode_is_not_a_mode_value_expect_rejected(mode):
    with pytest.raises(TargetRejectedError, match="joint 'yaw': unknown mode"):
        build({'yaw': JointTarget(mode)})


def test_when_mode_is_unknown_expect_rejected():
    with pytest.raises(TargetRejectedError, match="joint 'yaw': unknown mode 9"):
        build({'yaw': JointTarget(9)})


def test_when_target_is_not_a_joint_target_expect_rejected():
    with pytest.raises(TargetRejectedError, match="joint 'yaw': not a JointTarget"):
        build({'yaw': 1.0})


def actuator_state(names, online=True, **overrides):
    n = len(names)
    msg = ActuatorState()
    msg.name = list(names)
    msg.position = [float(i) for i in range(n)]
    msg.velocity = [0.5] * n
    msg.effort = [0.1] * n
    msg.temperature = [40.0] * n
    msg.online = [online] * n
    msg.error_code = [0] * n
    msg.mode = [ActuatorCmd.MODE_VELOCITY] * n
    msg.command = [0.2] * n
    for key, value in overrides.items():
        setattr(msg, key, value)
    return msg


def test_view_returns_the_latest_state_per_joint():
    view = JointStateView()
    assert view.handle(actuator_state(['a', 'b']), receive_ns=123)
    b = view.get('b')
    assert (b.position, b.velocity, b.effort, b.temperature) == (1.0, 0.5, 0.1, 40.0)
    assert b.online and b.error_code == 0 and b.mode == Mode.VELOCITY
    assert b.stamp_ns == 123  # zero header stamp: receive time
    assert view.get('c') is None


def test_targets_come_from_the_oldest_state_of_their_joints_or_from_none():
    view = JointStateView()
    view.handle(actuator_state(['a', 'b']), receive_ns=10)
    view.handle(actuator_state(['b']), receive_ns=20)
    states = view.snapshot()
    assert oldest_stamp(states, ['b']) == 20
    assert oldest_stamp(states, ['b', 'a']) == 10
    assert oldest_stamp(states, ['a', 'never_seen']) == 0  # not computed from states
    assert oldest_stamp(states, []) == 0


def test_messages_with_disjoint_joints_are_merged():
    view = JointStateView()
    view.handle(actuator_state(['a']), receive_ns=1)
    view.handle(actuator_state(['b'], online=False), receive_ns=2)
    assert set(view.snapshot()) == {'a', 'b'}
    assert view.all_online(['a'])
    assert not view.all_online(['a', 'b'])
    assert not view.all_online(['a', 'never_seen'])


def test_when_arrays_differ_in_length_expect_message_ignored_and_logged_once():
    lines = []

    class Log:
        def warning(self, message):
            lines.append(message)

    view = JointStateView(Log())
    assert not view.handle(actuator_state(['a', 'b'], velocity=[0.0]), receive_ns=1)
    assert not view.handle(actuator_state(['a', 'b'], velocity=[0.0]), receive_ns=2)
    assert view.snapshot() == {}
    assert lines == ['ignored /actuator_states: 2 names but 1 velocity']


def test_mode_and_command_may_be_left_empty():
    view = JointStateView()
    assert view.handle(actuator_state(['a'], mode=[], command=[]), receive_ns=1)
    assert view.get('a').mode == Mode.OFF


def test_readers_see_whole_updates_while_a_writer_updates():
    # Every message sets both joints to the same position; a reader must never see a mix.
    view = JointStateView()
    stop = threading.Event()

    def writer():
        i = 0
        while not stop.is_set():
            view.handle(actuator_state(['a', 'b'], position=[float(i)] * 2), receive_ns=i + 1)
            i += 1

    thread = threading.Thread(target=writer)
    thread.start()
    try:
        for _ in range(2000):
            snap = view.snapshot(['a', 'b'])
            if snap:
                assert snap['a'].position == snap['b'].position
    finally:
        stop.set()
        thread.join()
