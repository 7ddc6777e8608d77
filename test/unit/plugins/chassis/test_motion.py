"""MotionPlanner: ramps in the command's frame, modes, inverse kinematics, desaturation."""

import math

import pytest
from rm_base.control import PidGains, RampLimits
from rm_base.geometry import Twist2D, WheelKinematics, mecanum_wheels
from rm_plugins.chassis import MotionPlanner
from rm_plugins.chassis.modes import (
    ChassisModeParams,
    ChassisMotionMode,
    FollowParams,
    GyroParams,
    TwistParams,
)
from rm_plugins.chassis.motion import BASE_LINK_FRAME, GIMBAL_FRAME, ODOM_FRAME
from rm_plugins.chassis.spin_heading import SpinHeadingParams

RAW = ChassisMotionMode.RAW
FOLLOW = ChassisMotionMode.FOLLOW
GYRO = ChassisMotionMode.GYRO
DT = 0.01  # [s]
R = 0.1  # wheel radius [m]
KINEMATICS = WheelKinematics(mecanum_wheels(0.4, 0.4, R))  # lx + ly = 0.4 m
# launch 2 m/s^2 below 0.5 m/s, then 4 m/s^2; brake 8 m/s^2.
LINEAR = RampLimits(2.0, 4.0, 8.0, 0.5)
# wz: 10 rad/s^2 throughout.
ANGULAR = RampLimits(10.0, 10.0, 10.0, 0.0)
MODES = ChassisModeParams(
    FollowParams(PidGains(kp=5.0, output_limit=6.0, angle_mode=True)),
    TwistParams(0.5, 1.0),
    GyroParams(6.0),
)


def planner(max_wheel_speed=100.0):
    return MotionPlanner(KINEMATICS, MODES, LINEAR, ANGULAR, max_wheel_speed)


def run(p, mode, command, steps, frame=BASE_LINK_FRAME, **kwargs):
    out = None
    for _ in range(steps):
        out = p.update(mode, frame, command, DT, **kwargs)
    return out


def test_when_raw_from_rest_expect_the_launch_then_normal_ramp():
    p = planner()
    # 0.25 s at 2 m/s^2 reaches the 0.5 m/s launch speed; 0.1 s more at 4 m/s^2: 0.9 m/s.
    out = run(p, RAW, (3.0, 0.0, 0.0), 35)
    assert out.twist.vx == pytest.approx(0.9)
    assert out.saturation == 1.0
    # Every wheel rolls forward at v / r.
    assert out.wheel_targets == pytest.approx((9.0,) * 4)


def test_when_a_command_gives_an_acceleration_expect_it_instead_of_launch_and_normal():
    p = planner()
    # 1 m/s^2 for 0.5 s: 0.5 m/s, whatever the phase.
    out = run(p, RAW, (3.0, 0.0, 0.0), 50, accel=(1.0, None, None))
    assert out.twist.vx == pytest.approx(0.5)


def test_when_the_command_stops_expect_the_configured_brake_even_with_a_gentle_accel():
    p = planner()
    run(p, RAW, (1.0, 0.0, 0.0), 100, accel=(1.0, None, None))  # at 1.0 m/s after 1 s
    out = run(p, RAW, (0.0, 0.0, 0.0), 5, accel=(1.0, None, None))
    # Brake 8 m/s^2 for 50 ms: 1.0 - 0.4 = 0.6 m/s.
    assert out.twist.vx == pytest.approx(0.6)


def test_when_wheels_saturate_expect_one_scale_keeping_direction_and_no_ramp_windup():
    p = planner(max_wheel_speed=10.0)  # 1 m/s straight ahead at r = 0.1 m
    out = run(p, RAW, (2.0, 2.0, 0.0), 200)
    # Diagonal: FR/RL turn at (vx + vy) / r, so (vx + vy) <= 1 m/s, direction kept (45°).
    assert out.twist.vx == pytest.approx(0.5)
    assert out.twist.vy == pytest.approx(0.5)
    assert max(abs(w) for w in out.wheel_targets) == pytest.approx(10.0)
    # The ramp state was scaled too: each step it rises by 4 m/s^2 * 10 ms from 0.5 m/s
    # and is scaled back, k = 0.5 / 0.54; it never winds up towards 2 m/s.
    assert out.saturation == pytest.approx(0.5 / 0.54)
    # Released: braking starts from 0.5 m/s, not from the 2 m/s asked for.
    out = run(p, RAW, (0.0, 0.0, 0.0), 5)
    assert out.twist.vx == pytest.approx(0.5 - 8.0 * 0.05)


def test_when_switching_frames_expect_the_chassis_velocity_kept():
    p = planner()
    run(p, RAW, (1.0, 0.0, 0.0), 100)  # 1 m/s forward in base_link
    # Gimbal turned 90° left: "forward" there is chassis +y. The first step re-expresses
    # the ramp state, 1 m/s along chassis x = -1 m/s along gimbal y, then ramps towards
    # the new command (0.01 s at 2 m/s^2 launch: 0.02 m/s each axis).
    out = p.update(FOLLOW, GIMBAL_FRAME, (0.0, 0.0, 0.0), DT, yaw_joint=math.pi / 2)
    assert out.twist.vx == pytest.approx(1.0 - 8.0 * DT)  # braking at 8 m/s^2
    assert out.twist.vy == pytest.approx(0.0, abs=1e-9)


def test_when_raw_in_odom_expect_the_world_velocity_turned_into_the_chassis_frame():
    # The chassis faces +90° in odom (odom's x is 90° to its right: phi = -pi/2), so 1 m/s
    # along odom's x is 1 m/s to the chassis' right (-y); wz passes as its own rate.
    p = planner()
    out = run(p, RAW, (1.0, 0.0, 0.5), 200, frame=ODOM_FRAME, yaw_joint=-math.pi / 2)
    assert out.twist.vx == pytest.approx(0.0, abs=1e-9)
    assert out.twist.vy == pytest.approx(-1.0)
    assert out.twist.wz == pytest.approx(0.5)
    # In base_link the same phi is ignored: RAW is the chassis frame.
    out = run(planner(), RAW, (1.0, 0.0, 0.0), 200, yaw_joint=-math.pi / 2)
    assert (out.twist.vx, out.twist.vy) == pytest.approx((1.0, 0.0))


def test_when_following_a_gimbal_turned_left_expect_a_left_turn_and_gimbal_frame_motion():
    p = planner()
    out = run(p, FOLLOW, (1.0, 0.0, 0.0), 100, frame=GIMBAL_FRAME, yaw_joint=0.3)
    # PID: wz = kp * phi = 1.5 rad/s (left, towards the gimbal), reached at 10 rad/s^2.
    assert out.twist.wz == pytest.approx(1.5)
    # Forward in the gimbal frame is 0.3 rad left of chassis x (no look-ahead: the yaw
    # joint's measured rate is 0).
    heading = math.atan2(out.twist.vy, out.twist.vx)
    assert heading == pytest.approx(0.3)
    # With the joint closing at -1.5 rad/s the translation is turned by the angle phi has
    # on average over the coming step: -1.5 * (latency 0 + dt / 2) = -0.0075 rad.
    out = p.update(FOLLOW, GIMBAL_FRAME, (1.0, 0.0, 0.0), DT, yaw_joint=0.3, yaw_joint_rate=-1.5)
    assert math.atan2(out.twist.vy, out.twist.vx) == pytest.approx(0.3 - 0.0075)


def test_when_gyro_expect_the_spin_up_on_the_angular_ramp():
    p = planner()
    out = run(p, GYRO, (0.0, 0.0, 0.0), 30, frame=GIMBAL_FRAME)
    assert out.twist.wz == pytest.approx(3.0)  # 10 rad/s^2 for 0.3 s
    out = run(p, GYRO, (0.0, 0.0, 0.0), 100, frame=GIMBAL_FRAME)
    assert out.twist.wz == pytest.approx(6.0)


def closed_loop_planner():
    modes = ChassisModeParams(
        MODES.follow, MODES.twist, GyroParams(6.0, heading=SpinHeadingParams(5.0, 0.5))
    )
    return MotionPlanner(KINEMATICS, modes, LINEAR, ANGULAR, 100.0)


def test_when_gyro_with_a_heading_expect_the_spin_corrected_by_its_lag():
    p = closed_loop_planner()
    run(p, GYRO, (0.0, 0.0, 0.0), 100, frame=GIMBAL_FRAME, heading=0.0)  # held still
    out = p.update(GYRO, GIMBAL_FRAME, (0.0, 0.0, 0.0), DT, heading=0.0)
    assert p.spin_heading_error == pytest.approx(0.5)  # held to max_error
    assert out.twist.wz == pytest.approx(6.0 + 5.0 * 0.5)  # ramped spin plus the correction
    assert out.wheel_targets == pytest.approx(KINEMATICS.wheel_speeds((0.0, 0.0, 8.5)))
    # without a heading the spin is open loop, and the loop starts again when one comes
    assert p.update(GYRO, GIMBAL_FRAME, (0.0, 0.0, 0.0), DT).twist.wz == pytest.approx(6.0)
    assert p.update(GYRO, GIMBAL_FRAME, (0.0, 0.0, 0.0), DT, heading=1.0).twist.wz == 6.0


def test_when_not_gyro_expect_no_heading_correction_and_the_loop_forgotten():
    p = closed_loop_planner()
    run(p, GYRO, (0.0, 0.0, 0.0), 100, frame=GIMBAL_FRAME, heading=0.0)
    out = p.update(RAW, BASE_LINK_FRAME, (0.0, 0.0, 1.0), DT, heading=0.0)
    assert p.spin_heading_error == 0.0
    assert out.twist.wz < 6.0  # RAW's 1 rad/s, braking on the ramp, with nothing added


def test_when_reset_from_a_rolling_chassis_expect_the_ramps_to_start_there():
    p = planner()
    p.reset(Twist2D(1.0, 0.0, 2.0))
    out = p.update(RAW, BASE_LINK_FRAME, (1.0, 0.0, 2.0), DT)
    assert out.twist == pytest.approx((1.0, 0.0, 2.0))


def test_when_the_command_is_nan_expect_rejected():
    p = planner()
    with pytest.raises(ValueError, match='finite'):
        p.update(RAW, BASE_LINK_FRAME, (math.nan, 0.0, 0.0), DT)
