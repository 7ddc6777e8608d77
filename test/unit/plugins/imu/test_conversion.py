"""HiPNUC sample -> published frame: quaternion order, mounting, legacy Euler, bad values."""

import math

import numpy as np
import pytest
from rm_base.errors import InputRejectedError
from rm_base.geometry import quaternion_from_rpy, rotation_matrix_from_quaternion
from rm_base.hardware.protocols.hipnuc import ImuSample
from rm_plugins.imu import Mounting, reading_from_sample


def test_when_mounted_straight_expect_quaternion_reordered_to_x_y_z_w():
    # HiPNUC sends (w, x, y, z); ROS wants (x, y, z, w). A yaw of 90 deg:
    # q = (cos 45, 0, 0, sin 45) in HiPNUC order.
    c = math.cos(math.pi / 4)
    sample = ImuSample(quat=(c, 0.0, 0.0, c), gyr=(0.1, 0.2, 0.3), acc=(0.0, 0.0, 9.8))
    reading = reading_from_sample(sample, Mounting())
    assert reading.orientation == pytest.approx((0.0, 0.0, c, c))
    assert reading.angular_velocity == (0.1, 0.2, 0.3)
    assert reading.linear_acceleration == (0.0, 0.0, 9.8)


def test_when_only_euler_angles_come_expect_their_quaternion():
    # Legacy 0xD0 firmware: (roll, pitch, yaw) only.
    reading = reading_from_sample(ImuSample(euler=(0.1, -0.2, 1.0)), Mounting())
    assert reading.orientation == pytest.approx(quaternion_from_rpy(0.1, -0.2, 1.0))
    assert reading.angular_velocity is None and reading.linear_acceleration is None


def test_when_the_sensor_is_mounted_yawed_expect_data_in_the_frame_axes():
    # Sensor turned +90 deg about z in the frame: its x axis is the frame's y axis. A rate
    # about the sensor's x (1, 0, 0) is a rate about the frame's y: (0, 1, 0). The sensor
    # reading identity orientation means the frame is at -90 deg yaw in the world.
    mounting = Mounting((0.0, 0.0, math.pi / 2))
    sample = ImuSample(quat=(1.0, 0.0, 0.0, 0.0), gyr=(1.0, 0.0, 0.0), acc=(2.0, 0.0, 9.8))
    reading = reading_from_sample(sample, mounting)
    assert reading.angular_velocity == pytest.approx((0.0, 1.0, 0.0), abs=1e-12)
    assert reading.linear_acceleration == pytest.approx((0.0, 2.0, 9.8), abs=1e-12)
    expected = rotation_matrix_from_quaternion(quaternion_from_rpy(0.0, 0.0, -math.pi / 2))
    assert np.allclose(rotation_matrix_from_quaternion(reading.orientation), expected)


def test_covariance_is_rotated_with_the_data():
    # Variance 4 along the sensor's x becomes variance 4 along the frame's y.
    mounting = Mounting((0.0, 0.0, math.pi / 2))
    rotated = mounting.rotate_covariance((4.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0))
    assert rotated == pytest.approx((1.0, 0, 0, 0, 4.0, 0, 0, 0, 1.0), abs=1e-12)


@pytest.mark.parametrize(
    'sample',
    [
        ImuSample(quat=(0.0, 0.0, 0.0, 0.0)),
        ImuSample(quat=(math.nan, 0.0, 0.0, 1.0)),
        ImuSample(gyr=(0.0, math.inf, 0.0)),
        ImuSample(acc=(math.nan, 0.0, 9.8)),
    ],
    ids=['zero-quaternion', 'nan-quaternion', 'inf-rate', 'nan-accel'],
)
def test_when_a_value_is_bad_expect_the_sample_rejected(sample):
    with pytest.raises(InputRejectedError):
        reading_from_sample(sample, Mounting())
