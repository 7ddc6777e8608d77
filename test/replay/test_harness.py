"""The replay harness's parts on fakes: pacing, restamping, keeping streams live, jams.

No ROS node here: the simulated world, the clocks and the publishers are small fakes.
"""

from __future__ import annotations

import threading
from types import SimpleNamespace

import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Twist
from rclpy.serialization import serialize_message
from rm_base.sim import FaultKind

from replay.harness import ReplayError, _Clock, _CommandPublisher, _Faults, _Pacer
from replay.scenarios import Jam
from rm_msgs.msg import GimbalCmd

MS = 1_000_000  # [ns]


class FakeWorld:
    """Sim time by hand; a trigger motor whose torque the test sets; fault calls logged."""

    def __init__(self) -> None:
        self.time_ns = 0
        self.lock = threading.Lock()
        self.calls: list[tuple] = []
        self.model = SimpleNamespace(torque=0.0, velocity=0.0)

    def motor(self, name):
        return SimpleNamespace(model=self.model)

    def inject(self, motor, fault):
        self.calls.append(('inject', motor, fault.kind))

    def clear_faults(self, motor=None, kind=None):
        self.calls.append(('clear', motor, kind))


class FakeRosClock:
    def __init__(self) -> None:
        self.ns = 1_700_000_000 * 10**9

    def now(self):
        self.ns += MS
        ns = self.ns
        return SimpleNamespace(
            nanoseconds=ns,
            to_msg=lambda: Time(sec=ns // 10**9, nanosec=ns % 10**9),
        )


class FakePublisher:
    def __init__(self) -> None:
        self.published = []

    def publish(self, msg):
        self.published.append(msg)


def command_publisher(world, offsets_ns, msg_class, topic='/gimbal_cmd'):
    clock = _Clock(world)
    stop = threading.Event()
    pacer = _Pacer([(topic, o) for o in offsets_ns], clock, stop)
    publisher, log = FakePublisher(), []
    adapter = _CommandPublisher(
        topic, publisher, msg_class, offsets_ns, pacer, clock, FakeRosClock(), log
    )
    return adapter, publisher, log, clock


def test_when_the_sim_lags_expect_a_message_held_until_the_sim_reaches_its_time():
    world = FakeWorld()
    clock = _Clock(world)
    stop = threading.Event()
    pacer = _Pacer([('/a', 0), ('/a', 50 * MS)], clock, stop)
    assert pacer.wait_turn('/a') == 0  # due at once
    released = []
    waiter = threading.Thread(target=lambda: released.append(pacer.wait_turn('/a')))
    waiter.start()
    waiter.join(timeout=0.2)  # 0.2 s of wall time, but the sim stands still
    assert waiter.is_alive() and not released
    world.time_ns = 50 * MS  # the sim reaches the message's bag time
    waiter.join(timeout=2.0)
    assert released == [50 * MS]


def test_when_play_sends_another_topic_than_the_bag_has_expect_an_error():
    pacer = _Pacer([('/a', 0)], _Clock(FakeWorld()), threading.Event())
    with pytest.raises(ReplayError, match=r'message 0: play\(\) sent /b, the bag has /a'):
        pacer.wait_turn('/b')


def test_when_stopped_expect_the_waiting_message_dropped():
    stop = threading.Event()
    pacer = _Pacer([('/a', 10 * MS)], _Clock(FakeWorld()), stop)
    stop.set()
    assert pacer.wait_turn('/a') is None


def test_every_header_is_stamped_with_now_at_publish():
    world = FakeWorld()
    adapter, publisher, log, _ = command_publisher(world, [0], GimbalCmd)
    bag_msg = GimbalCmd(mode=GimbalCmd.TRACK)
    bag_msg.header.stamp.sec = 3  # relative to the bag start
    bag_msg.target.header.stamp.sec = 3
    bag_msg.target.header.frame_id = 'odom'
    adapter.publish(serialize_message(bag_msg))
    (sent,) = publisher.published
    stamp_ns = sent.header.stamp.sec * 10**9 + sent.header.stamp.nanosec
    assert stamp_ns == log[0].stamp_ns > 1_700_000_000 * 10**9
    assert sent.target.header.stamp == sent.header.stamp
    assert (sent.mode, sent.target.header.frame_id) == (GimbalCmd.TRACK, 'odom')


def test_while_the_stream_continues_expect_the_last_message_sent_again_when_held_back(monkeypatch):
    world = FakeWorld()
    # A 20 ms stream of three messages, then a pause of 1 s, then one more.
    offsets = [0, 20 * MS, 40 * MS, 1040 * MS]
    adapter, publisher, log, clock = command_publisher(world, offsets, Twist, '/vel_cmd')
    wall = [0.0]
    monkeypatch.setattr(clock, 'wall', lambda: wall[0])
    adapter.publish(serialize_message(Twist()))
    wall[0] = 0.05
    adapter.refresh()  # less than REFRESH_PERIODS (3 x 20 ms) since the last one: nothing
    assert len(publisher.published) == 1
    wall[0] = 0.065
    adapter.refresh()  # the sim lags, 3 periods of wall time went by: sent again
    assert len(publisher.published) == 2 and log[-1].refresh
    assert log[-1].bag_t == 0.0
    world.time_ns = 40 * MS
    adapter.publish(serialize_message(Twist()))
    adapter.publish(serialize_message(Twist()))  # the third: a pause follows in the bag
    wall[0] = 1.0
    adapter.refresh()  # the bag pauses here: no refresh (a dropout reaches the robot)
    assert len(publisher.published) == 4
    assert [s.refresh for s in log] == [False, True, False, False]


def test_a_jam_locks_at_the_next_drive_forward_and_frees_after_a_sustained_reverse():
    world = FakeWorld()
    model = world.model
    faults = _Faults(world, (Jam('trigger', at_s=1.0, torque=0.5, speed=1.0, free_s=0.05),))
    model.torque, model.velocity = 1.5, 10.0
    faults.update(0.9)  # not armed yet
    assert world.calls == []
    model.torque, model.velocity = -1.5, 8.0  # braking at the end of a step
    faults.update(1.0)
    model.torque, model.velocity = 0.8, 0.1  # holding at the end of a step: not moving
    faults.update(1.01)
    assert world.calls == []
    model.torque, model.velocity = 1.5, 3.0  # the next step drives a ball: it wedges
    faults.update(1.03)
    assert world.calls == [('inject', 'trigger', FaultKind.JAM)]
    model.torque, model.velocity = -0.8, 0.0  # the lock's recoil, 20 ms: still jammed
    faults.update(1.04)
    faults.update(1.06)
    model.torque = 1.5  # stalled, pushing on
    faults.update(1.07)
    model.torque = -1.5  # BLOCK reverses, 50 ms: the ball comes free
    for t in (1.20, 1.22, 1.24):
        faults.update(t)
    assert world.calls[-1] == ('inject', 'trigger', FaultKind.JAM)
    faults.update(1.25)
    assert world.calls[-1] == ('clear', 'trigger', FaultKind.JAM)
    assert [r.action for r in faults.records] == ['armed', 'wedged', 'clear']
    assert [r.t for r in faults.records] == [1.0, 1.03, 1.25]
