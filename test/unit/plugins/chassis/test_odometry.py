"""Chassis odometry: wheel forward kinematics, midpoint integration, IMU yaw with an offset."""

import math

import pytest
from rm_base.errors import InputRejectedError
from rm_base.geometry import WheelKinematics, mecanum_wheels
from rm_plugins.chassis import Odometry, YawSource

R = 0.1  # wheel radius [m]
KINEMATICS = WheelKinematics(mecanum_wheels(0.2, 0.2, R))


def wheels(vx=0.0, vy=0.0, wz=0.0):
    """Wheel speeds [rad/s] of the standard X layout (rm_base.geometry.kinematics)."""
    return KINEMATICS.inverse((vx, vy, wz)).tolist()


class Wheels:
    """Wheel encoders: angles advanced by the speeds of a twist over dt."""

    def __init__(self):
        self.angles = [0.0] * 4

    def drive(self, odom, dt, vx=0.0, vy=0.0, wz=0.0, **kwargs):
        speeds = wheels(vx, vy, wz)
        self.angles = [a + w * dt for a, w in zip(self.angles, speeds, strict=True)]
        return odom.update(self.angles, speeds, **kwargs)


def started():
    """Odometry that has taken its first wheel angles (all zero) as the reference."""
    odom, encoders = Odometry(KINEMATICS), Wheels()
    encoders.drive(odom, 0.0)
    return odom, encoders


def test_when_driving_forward_expect_x_to_grow_by_the_wheel_travel():
    odom, encoders = started()
    for _ in range(100):
        encoders.drive(odom, 0.01, vx=0.5)
    # 0.5 m/s for 100 x 10 ms = 0.5 m along x.
    assert odom.pose.x == pytest.approx(0.5)
    assert odom.pose.y == pytest.approx(0.0, abs=1e-12)
    assert odom.twist.vx == pytest.approx(0.5)
    assert odom.yaw_source is YawSource.WHEELS


def test_when_the_first_update_comes_expect_only_a_reference_not_motion():
    odom = Odometry(KINEMATICS)
    odom.update([100.0, -3.0, 7.0, 1.0], wheels())
    assert odom.pose == (0.0, 0.0, 0.0)


def test_when_steps_are_late_expect_no_distance_lost():
    odom, encoders = started()
    # The same 0.5 m, in 10 ms steps and then in one 0.5 s step (a stalled tick): the
    # encoders counted every radian, so nothing is lost.
    for _ in range(50):
        encoders.drive(odom, 0.01, vx=0.5)
    encoders.drive(odom, 0.5, vx=0.5)
    assert odom.pose.x == pytest.approx(0.5)


def test_when_driving_an_arc_expect_the_circle_from_midpoint_integration():
    odom, encoders = started()
    # vx = 1 m/s, wz = pi/2 rad/s for 1 s: a quarter circle of radius 2/pi m, ending at
    # (r, r) with yaw pi/2. Midpoint integration at 1 ms is exact to ~1e-7 m.
    for _ in range(1000):
        encoders.drive(odom, 0.001, vx=1.0, wz=math.pi / 2)
    radius = 2.0 / math.pi
    assert odom.pose.x == pytest.approx(radius, abs=1e-5)
    assert odom.pose.y == pytest.approx(radius, abs=1e-5)
    assert odom.pose.yaw == pytest.approx(math.pi / 2)


def test_when_imu_yaw_appears_expect_continuity_then_the_imu_changes():
    odom, encoders = started()
    for _ in range(100):
        encoders.drive(odom, 0.01, wz=1.0)  # wheels: 1 rad
    assert odom.pose.yaw == pytest.approx(1.0)
    # The IMU reads 2.5 rad in its own reference: the odom yaw stays 1 rad ...
    encoders.drive(odom, 0.01, absolute_yaw=2.5)
    assert odom.pose.yaw == pytest.approx(1.0)
    assert odom.yaw_source is YawSource.IMU
    # ... and follows the IMU's changes from there, whatever the wheels say.
    encoders.drive(odom, 0.01, wz=5.0, absolute_yaw=2.7)
    assert odom.pose.yaw == pytest.approx(1.2)


def test_when_imu_yaw_wraps_expect_an_unwrapped_odom_yaw():
    odom, encoders = started()
    encoders.drive(odom, 0.01, absolute_yaw=3.1)
    encoders.drive(odom, 0.01, absolute_yaw=-3.1)  # +0.0832 rad across the wrap
    assert odom.pose.yaw == pytest.approx(2.0 * math.pi - 6.2)


def test_when_imu_stops_expect_the_wheels_turn_from_the_last_yaw():
    odom, encoders = started()
    encoders.drive(odom, 0.01, absolute_yaw=0.0)
    encoders.drive(odom, 0.01, absolute_yaw=0.3)
    encoders.drive(odom, 0.1, wz=1.0)  # no IMU: +0.1 rad from the wheels
    assert odom.pose.yaw == pytest.approx(0.4)
    assert odom.yaw_source is YawSource.WHEELS


def test_when_imu_returns_after_a_gap_expect_its_reference_kept():
    odom, encoders = started()
    encoders.drive(odom, 0.01, absolute_yaw=2.0)  # reference: IMU 2.0 = odom 0
    encoders.drive(odom, 0.1, wz=1.0)  # gap: the wheels say +0.1 rad (they slipped)
    encoders.drive(odom, 0.01, absolute_yaw=2.05)  # the IMU says +0.05: it wins
    assert odom.pose.yaw == pytest.approx(0.05)


def test_when_the_imu_reference_is_released_expect_a_new_one_and_continuity():
    odom, encoders = started()
    encoders.drive(odom, 0.01, absolute_yaw=2.0)
    encoders.drive(odom, 0.1, wz=1.0)  # odom 0.1
    odom.release_absolute_yaw()
    encoders.drive(odom, 0.01, absolute_yaw=-1.0)  # a restarted IMU: new reference
    assert odom.pose.yaw == pytest.approx(0.1)
    encoders.drive(odom, 0.01, absolute_yaw=-0.9)
    assert odom.pose.yaw == pytest.approx(0.2)


def test_when_the_wheel_reference_restarts_expect_the_pose_kept():
    odom, encoders = started()
    encoders.drive(odom, 0.1, vx=1.0)  # 0.1 m
    # The bridge restarted: the angles start again near 0.
    odom.restart_wheel_reference()
    odom.update([0.5, 0.2, 0.1, 0.3], wheels(), absolute_yaw=None)
    assert odom.pose.x == pytest.approx(0.1)
    # Motion from the new reference counts again: 0.03 m more.
    step = 0.03 / R
    odom.update([0.5 + step, 0.2 + step, 0.1 + step, 0.3 + step], wheels())
    assert odom.pose.x == pytest.approx(0.13)


def test_when_a_wheel_angle_is_nan_expect_rejected_and_the_pose_kept():
    odom, encoders = started()
    encoders.drive(odom, 0.1, vx=1.0)
    with pytest.raises(InputRejectedError):
        odom.update([math.nan, 0.0, 0.0, 0.0], wheels())
    assert odom.pose.x == pytest.approx(0.1)
