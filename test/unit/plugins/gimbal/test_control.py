"""Gimbal maths: the axis loop (angle PID -> world rate -> joint velocity), sight rates, poses."""

import math

import pytest
from rm_base.control import PidGains
from rm_plugins.gimbal import AxisLoop, PlanarPose, Smoother, sight_rates

GAINS = PidGains(kp=10.0, output_limit=5.0, angle_mode=True)


def test_when_on_target_and_the_base_spins_expect_the_joint_to_counter_rotate():
    # Zero error, chassis turning at +3 rad/s: the joint must turn at -3 rad/s so the
    # world rate stays 0.
    loop = AxisLoop(GAINS, max_joint_velocity=20.0)
    out = loop.update(target=1.0, measured=1.0, rate_feedforward=0.0, base_rate=3.0, dt=0.002)
    assert out.world_rate == 0.0
    assert out.joint_velocity == -3.0


def test_angle_error_gives_kp_times_error_plus_feedforward():
    # 0.1 rad behind with kp 10 -> 1 rad/s, plus 0.5 rad/s feed-forward = 1.5 rad/s.
    loop = AxisLoop(GAINS, max_joint_velocity=20.0)
    out = loop.update(target=0.1, measured=0.0, rate_feedforward=0.5, base_rate=0.0, dt=0.002)
    assert out.world_rate == pytest.approx(1.5)
    assert out.joint_velocity == pytest.approx(1.5)


def test_the_error_is_taken_the_short_way_round():
    # From 3.1 rad to -3.1 rad is +0.083 rad across pi, not -6.2 rad.
    loop = AxisLoop(GAINS, max_joint_velocity=20.0)
    out = loop.update(target=-3.1, measured=3.1, rate_feedforward=0.0, base_rate=0.0, dt=0.002)
    assert out.world_rate == pytest.approx(10.0 * (2 * math.pi - 6.2))


def test_world_rate_and_joint_velocity_are_bounded():
    loop = AxisLoop(GAINS, max_joint_velocity=4.0)
    out = loop.update(target=2.0, measured=0.0, rate_feedforward=3.0, base_rate=-2.0, dt=0.002)
    assert out.world_rate == 5.0  # output_limit
    assert out.joint_velocity == 4.0  # 5 - (-2) = 7, bounded to 4


@pytest.mark.parametrize(
    ('joint_angle', 'wanted', 'expected'),
    [
        # 0.05 rad inside the upper limit 0.3 with gain 20: at most 20 * 0.05 = 1 rad/s on.
        (0.25, 3.0, 1.0),
        # Past the upper limit by 0.02: driven back at 20 * -0.02 = -0.4 rad/s at least.
        (0.32, 3.0, -0.4),
        # Moving away from the limit is not restricted.
        (0.32, -3.0, -3.0),
        # Far from both limits: as wanted.
        (0.0, 3.0, 3.0),
    ],
)
def test_near_a_joint_limit_expect_the_velocity_bounded(joint_angle, wanted, expected):
    loop = AxisLoop(PidGains(output_limit=10.0, angle_mode=True), max_joint_velocity=20.0)
    out = loop.update(
        target=0.0,
        measured=0.0,
        rate_feedforward=wanted,
        base_rate=0.0,
        dt=0.002,
        joint_angle=joint_angle,
        joint_limits=(-0.5, 0.3),
        limit_gain=20.0,
    )
    assert out.joint_velocity == pytest.approx(expected)


def test_a_loop_needs_angle_mode_gains():
    with pytest.raises(ValueError, match='angle_mode'):
        AxisLoop(PidGains(kp=1.0), 1.0)


def test_pose_extrapolation_turns_and_moves():
    # Facing +y (yaw pi/2), 1 m/s forward for 0.1 s: +0.1 m in y. Spinning 1 rad/s: +0.1 rad.
    pose = PlanarPose(1.0, 2.0, math.pi / 2).extrapolated(1.0, 0.0, 0.0, 0.1)
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((1.0, 2.1, math.pi / 2))
    spun = PlanarPose(0.0, 0.0, 0.0).extrapolated(0.0, 0.0, 1.0, 0.1)
    assert spun.yaw == pytest.approx(0.1)
    # A point 1 m ahead of a robot at (1, 2) facing +y is at (1, 3).
    assert PlanarPose(1.0, 2.0, math.pi / 2).to_world(1.0, 0.0) == pytest.approx((1.0, 3.0))


def test_an_angle_smoother_goes_the_short_way_across_pi():
    s = Smoother(0.1, angle=True)
    s.update(3.1, 0.01)
    # Next sample -3.1 is 0.083 rad further on, not 6.2 rad back: the output moves by a
    # fraction (1 - exp(-0.1)) of +0.083.
    out = s.update(-3.1, 0.01)
    assert out == pytest.approx(3.1 + (2 * math.pi - 6.2) * (1 - math.exp(-0.1)))


def test_a_smoother_with_zero_time_constant_passes_samples_through():
    s = Smoother(0.0)
    assert s.update(1.0, 0.01) == 1.0
    assert s.update(-2.0, 0.01) == -2.0


def test_sight_rates_of_a_point_passed_sideways():
    # A point 4 m ahead, 1 m up; the pivot moves left at 2 m/s, so the point moves right
    # relative to it: offset velocity (0, -2, 0). Bearing rate = (x vy - y vx) / d^2
    # = (4 * -2) / 16 = -0.5 rad/s (turn right). Pitch -atan2(z, d) with d' = 0:
    # rate = -(d z' - z d') / (d^2 + z^2) = 0.
    assert sight_rates((4.0, 0.0, 1.0), (0.0, -2.0, 0.0)) == pytest.approx((-0.5, 0.0))


def test_sight_rates_of_an_approaching_point_above():
    # 4 m ahead, 1 m up, closing at 2 m/s: d' = -2. Pitch rate = -(4 * 0 - 1 * -2) / 17
    # = -2/17 rad/s: the barrel rises (negative pitch) as the point gets closer.
    assert sight_rates((4.0, 0.0, 1.0), (-2.0, 0.0, 0.0)) == pytest.approx((0.0, -2.0 / 17.0))
    assert sight_rates((0.0, 0.0, 1.0), (1.0, 1.0, 0.0)) == (0.0, 0.0)  # straight above


def test_velocity_of_a_body_point_includes_the_spin():
    # Robot at yaw 0 spinning at 2 rad/s, still: the point (0.5, 0) moves at 2 * 0.5 = 1 m/s
    # to the left (+y). Facing +y (yaw pi/2), driving forward at 1 m/s: (-0, 1) -> (0, 1).
    assert PlanarPose(0.0, 0.0, 0.0).velocity_of(0.5, 0.0, 0.0, 0.0, 2.0) == pytest.approx(
        (0.0, 1.0)
    )
    assert PlanarPose(0.0, 0.0, math.pi / 2).velocity_of(0.0, 0.0, 1.0, 0.0, 0.0) == pytest.approx(
        (0.0, 1.0)
    )
