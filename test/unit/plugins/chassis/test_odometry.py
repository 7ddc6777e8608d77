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


def test_when_driving_forward_expect_x_to_grow_by_v_times_t():
    odom = Odometry(KINEMATICS)
    for _ in range(100):
        odom.update(wheels(vx=0.5), 0.01)
    # 0.5 m/s for 100 x 10 ms = 0.5 m along x.
    assert odom.pose.x == pytest.approx(0.5)
    assert odom.pose.y == pytest.approx(0.0, abs=1e-12)
    assert odom.twist.vx == pytest.approx(0.5)
    assert odom.yaw_source is YawSource.WHEELS


def test_when_driving_an_arc_expect_the_circle_from_midpoint_integration():
    odom = Odometry(KINEMATICS)
    # vx = 1 m/s, wz = pi/2 rad/s for 1 s: a quarter circle of radius 2/pi m, ending at
    # (r, r) with yaw pi/2. Midpoint integration at 1 ms is exact to ~1e-7 m.
    for _ in range(1000):
        odom.update(wheels(vx=1.0, wz=math.pi / 2), 0.001)
    radius = 2.0 / math.pi
    assert odom.pose.x == pytest.approx(radius, abs=1e-5)
    assert odom.pose.y == pytest.approx(radius, abs=1e-5)
    assert odom.pose.yaw == pytest.approx(math.pi / 2)


def test_when_imu_yaw_appears_expect_continuity_then_the_imu_changes():
    odom = Odometry(KINEMATICS)
    for _ in range(100):
        odom.update(wheels(wz=1.0), 0.01)  # wheels: 1 rad
    assert odom.pose.yaw == pytest.approx(1.0)
    # The IMU reads 2.5 rad in its own reference: the odom yaw stays 1 rad ...
    odom.update(wheels(), 0.01, absolute_yaw=2.5)
    assert odom.pose.yaw == pytest.approx(1.0)
    assert odom.yaw_source is YawSource.IMU
    # ... and follows the IMU's changes from there, whatever the wheels say.
    odom.update(wheels(wz=5.0), 0.01, absolute_yaw=2.7)
    assert odom.pose.yaw == pytest.approx(1.2)


def test_when_imu_yaw_wraps_expect_an_unwrapped_odom_yaw():
    odom = Odometry(KINEMATICS)
    odom.update(wheels(), 0.01, absolute_yaw=3.1)
    odom.update(wheels(), 0.01, absolute_yaw=-3.1)  # +0.0832 rad across the wrap
    assert odom.pose.yaw == pytest.approx(2.0 * math.pi - 6.2)


def test_when_imu_stops_expect_wheel_integration_from_the_last_yaw():
    odom = Odometry(KINEMATICS)
    odom.update(wheels(), 0.01, absolute_yaw=0.0)
    odom.update(wheels(), 0.01, absolute_yaw=0.3)
    odom.update(wheels(wz=1.0), 0.1)  # no IMU: +0.1 rad from the wheels
    assert odom.pose.yaw == pytest.approx(0.4)
    assert odom.yaw_source is YawSource.WHEELS


def test_when_a_wheel_speed_is_nan_expect_rejected_and_the_pose_kept():
    odom = Odometry(KINEMATICS)
    odom.update(wheels(vx=1.0), 0.1)
    with pytest.raises(InputRejectedError):
        odom.update([math.nan, 0.0, 0.0, 0.0], 0.1)
    assert odom.pose.x == pytest.approx(0.1)
