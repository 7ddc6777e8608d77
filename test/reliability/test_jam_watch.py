"""The soak's JamWatch: a jam counts only where the joint's loop must reach its clamp.

The GM6020 yaw has the standard robot's velocity loop (standard.yaml): kp 1.5 N·m/(rad/s),
ki 10, integral limit 0.6 N·m, clamp 1.2 N·m, so a stalled yaw reaches its clamp only when
asked for (0.99 * 1.2 - 0.6) / 1.5 = 0.39 rad/s or more. Lockstep, exact time.
"""

from types import SimpleNamespace

import pytest
from rm_base.control.pid import PidGains
from rm_base.hardware import MODE_POSITION, MODE_VELOCITY
from rm_base.joints import Mode
from rm_base.sim import Fault

from reliability.jam_watch import FeedSpan, JamWatch, power_scale, stall_demand, stall_push
from reliability.rigs import LockstepRig

YAW = {
    'type': 'gm6020',
    'id': 1,
    'max_effort': 1.2,
    'velocity_pid': {'kp': 1.5, 'ki': 10.0, 'output_limit': 1.2, 'integral_limit': 0.6},
    'position_pid': {'kp': 15.0, 'output_limit': 20.0},
}
STANDARD_YAW = PidGains(kp=1.5, ki=10.0, output_limit=1.2, integral_limit=0.6)


@pytest.fixture
def rig():
    r = LockstepRig({'yaw': YAW})
    yield r
    r.close()


def _jam_for(rig, seconds, command):
    """Settle 0.2 s, jam the yaw, run; return the watch sampled every tick."""
    rig.step(200, {'yaw': command})
    rig.world.inject('yaw', Fault.jam())
    watch = JamWatch(rig.hw.actuators['yaw'])
    shown_at = None
    for tick in range(round(seconds * 1000)):
        rig.step(1, {'yaw': command})
        if watch.sample() and shown_at is None:
            shown_at = tick
    return watch, shown_at


def test_a_yaw_holding_its_aim_when_it_jams_never_reaches_its_clamp_and_is_not_judged(rig):
    # a gimbal holding its target asks the yaw for a few hundredths of a rad/s
    watch, shown_at = _jam_for(rig, 3.0, {'mode': MODE_VELOCITY, 'velocity': 0.05})
    assert shown_at is None
    assert 0.5 < watch.peak_output / watch.clamp < 0.99  # it pushes, but not to the clamp
    assert not watch.judged
    assert 'asked a stalled loop for up to 56%' in watch.note()


def test_a_yaw_asked_to_turn_when_it_jams_reaches_its_clamp_and_is_judged(rig):
    watch, shown_at = _jam_for(rig, 1.0, {'mode': MODE_VELOCITY, 'velocity': 2.0})
    assert shown_at is not None and shown_at < 100
    assert watch.judged


def test_a_position_far_from_where_the_joint_jammed_is_judged_and_shows(rig):
    watch, shown_at = _jam_for(rig, 1.0, {'mode': MODE_POSITION, 'position': 3.0})
    assert shown_at is not None and watch.judged


def test_just_below_the_saturating_speed_is_not_judged_just_above_is(rig):
    assert stall_push(STANDARD_YAW, 0.38) < 0.99 * 1.2 <= stall_push(STANDARD_YAW, 0.40)


@pytest.mark.parametrize(
    ('gains', 'speed', 'push'),
    [
        (PidGains(kp=1.5, ki=10.0, output_limit=1.2, integral_limit=0.6), 0.1, 0.75),
        (PidGains(kp=1.5, ki=10.0, output_limit=1.2, integral_limit=0.6), -0.1, 0.75),
        (PidGains(kp=1.5, ki=10.0, output_limit=1.2, integral_limit=0.6), 5.0, 1.2),
        (PidGains(kp=1.5, ki=0.0, output_limit=1.2, integral_limit=0.6), 0.1, 0.15),  # no I
        (PidGains(kp=0.5, ki=5.0, output_limit=6.0), 1.0, 6.0),  # I limited by the output
        # the standard wheel: no integral for an error of 5 rad/s or more
        (PidGains(kp=1.5, ki=10.0, output_limit=4.0, integral_limit=1.5,
                  integral_separation=5.0), 4.9, 4.0),
        (PidGains(kp=1.5, ki=10.0, output_limit=4.0, integral_limit=1.5,
                  integral_separation=5.0), 2.0, 4.0),
        (PidGains(kp=1.5, ki=10.0, output_limit=4.0, integral_limit=1.5,
                  integral_separation=2.0), 2.0, 3.0),
    ],
)
def test_stall_push_is_the_proportional_term_plus_the_wound_up_integral(gains, speed, push):
    assert stall_push(gains, speed) == pytest.approx(push)


def _actuator(max_velocity=30.0):
    config = SimpleNamespace(velocity_pid=STANDARD_YAW, position_pid=PidGains(kp=15.0))
    return SimpleNamespace(config=config, max_velocity=max_velocity, max_effort=1.2)


def _command(mode, position=0.0, velocity=0.0, effort=0.0, kp=0.0, kd=0.0):
    return SimpleNamespace(
        mode=mode, position=position, velocity=velocity, effort=effort, kp=kp, kd=kd
    )


@pytest.mark.parametrize(
    ('command', 'position', 'demand'),
    [
        (None, 0.0, 0.0),
        (_command(Mode.OFF, velocity=9.0), 0.0, 0.0),
        (_command(Mode.EFFORT, effort=-0.9), 0.0, 0.9),
        (_command(Mode.VELOCITY, velocity=0.2), 0.0, 0.9),
        (_command(Mode.VELOCITY, velocity=100.0), 0.0, 1.2),
        # POSITION: 15 * 0.01 rad = 0.15 rad/s -> 1.5 * 0.15 + 0.6
        (_command(Mode.POSITION, position=1.01), 1.0, 0.825),
        (_command(Mode.POSITION, position=1.0, velocity=0.1), 1.0, 0.75),  # feed-forward
        # MIT, stalled: kp * error + kd * velocity + effort, unclamped
        (_command(Mode.MIT, position=1.0, velocity=2.0, kp=3.0, kd=0.5, effort=0.2), 0.0, 4.2),
    ],
)
def test_stall_demand_follows_each_mode(command, position, demand):
    assert stall_demand(_actuator(), command, position) == pytest.approx(demand)


def test_a_velocity_target_beyond_the_joint_limit_asks_only_the_limit():
    slow = _actuator(max_velocity=0.1)
    assert stall_demand(slow, _command(Mode.VELOCITY, velocity=5.0), 0.0) == pytest.approx(0.75)


def test_a_power_limited_joint_shows_at_the_clamp_times_the_stages_factor():
    output = [0.0]
    actuator = _actuator()
    actuator.command = _command(Mode.VELOCITY, velocity=5.0)
    actuator.state = lambda: SimpleNamespace(command=output[0], mode=Mode.VELOCITY, position=0.0)
    factor = [1.0]
    watch = JamWatch(actuator, lambda: factor[0])
    output[0] = 0.6
    assert not watch.sample()  # half the clamp, nothing scaled
    factor[0] = 0.5
    assert watch.sample()  # the stage halved the group: half the clamp is all it may push
    assert watch.judged and 'least power factor 0.50' in watch.note()
    assert not JamWatch(actuator).sample()  # no power stage: the clamp itself


def test_power_scale_reads_the_stage_of_the_joints_group():
    stage = SimpleNamespace(joints=('wheel_fl', 'wheel_fr'), last=None)
    hardware = SimpleNamespace(power_limits={'chassis': stage})
    scale = power_scale(hardware, 'wheel_fr')
    assert scale() == 1.0  # the stage has not scaled anything yet
    stage.last = SimpleNamespace(scale=0.8)
    assert scale() == 0.8
    assert power_scale(hardware, 'yaw') is None


def test_the_feed_span_is_the_longest_unbroken_push():
    span = FeedSpan(effort_threshold=1.0)
    for now, feeding in [(0.00, True), (0.02, True), (0.07, True), (0.09, False),
                         (0.30, True), (0.40, True), (0.52, True), (0.60, False)]:
        span.sample(feeding, -1.5, now)  # pushing backwards counts too (BLOCK)
    assert span.longest == pytest.approx(0.22)  # 0.30 -> 0.52, not 0.00 -> 0.52
    assert span.longest_fed == pytest.approx(0.22)


def test_a_feed_seen_once_lasts_nothing():
    span = FeedSpan(effort_threshold=1.0)
    span.sample(False, 1.5, 0.0)
    span.sample(True, 1.5, 0.1)
    span.sample(False, 1.5, 0.2)
    assert span.longest == 0.0


def test_a_feed_that_does_not_push_past_the_jam_effort_does_not_count():
    # FEED while the friction wheels spin up: the trigger waits, at rest
    span = FeedSpan(effort_threshold=1.0)
    for now, effort in [(0.0, 0.0), (0.1, 0.2), (0.2, 1.2), (0.25, 1.4), (0.3, 0.9), (0.4, 1.5)]:
        span.sample(True, effort, now)
    assert span.longest == pytest.approx(0.05)  # 0.2 -> 0.25; at 1.0 itself it does not push
    assert span.longest_fed == pytest.approx(0.4)
