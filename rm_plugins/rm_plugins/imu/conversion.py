"""HiPNUC samples -> REP 103 values in the published frame (no ROS, no I/O).

A HiPNUC sample (``rm_base.hardware.protocols.hipnuc.ImuSample``) is already SI but its
quaternion is in (w, x, y, z) order and everything is in the sensor's own axes. This
module reorders the quaternion to ROS order (x, y, z, w) and rotates the sample into the
frame the plugin publishes in, given the sensor's mounting in that frame
(``R_frame_sensor``): for a sensor mounted rotated by ``mount_rpy`` in ``frame_id``,

- orientation: world <- frame = (world <- sensor) @ (sensor <- frame)
- angular velocity and specific force: v_frame = R_frame_sensor @ v_sensor.

With an identity mounting the values are passed through (only reordered).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from rm_base.errors import InputRejectedError
from rm_base.geometry import (
    Quaternion,
    normalize_quaternion,
    quaternion_from_rpy,
    quaternion_multiply,
    rotation_matrix_from_rpy,
)
from rm_base.hardware.protocols.hipnuc import ImuSample

Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class ImuReading:
    """One IMU sample in the published frame; a field the sample did not carry is None.

    Attributes:
        orientation: world <- frame, ROS order (x, y, z, w).
        angular_velocity: (x, y, z) [rad/s] in the frame.
        linear_acceleration: specific force (x, y, z) [m/s²] in the frame (+g up at rest).
    """

    orientation: Quaternion | None
    angular_velocity: Vector3 | None
    linear_acceleration: Vector3 | None


class Mounting:
    """How the sensor sits in the published frame.

    Args:
        rpy: (roll, pitch, yaw) [rad] of the sensor's axes in the frame
            (``R_frame_sensor = Rz(yaw) Ry(pitch) Rx(roll)``).

    Raises:
        InputRejectedError: an angle is NaN or infinite.
    """

    def __init__(self, rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
        roll, pitch, yaw = rpy
        self.identity = roll == 0.0 and pitch == 0.0 and yaw == 0.0
        self.rotation: NDArray[np.float64] = rotation_matrix_from_rpy(roll, pitch, yaw)
        # sensor <- frame, applied on the right of world <- sensor.
        q = quaternion_from_rpy(roll, pitch, yaw)
        self.sensor_from_frame = Quaternion(-q.x, -q.y, -q.z, q.w)

    def rotate_vector(self, v: Vector3) -> Vector3:
        """Return v (sensor axes) in the frame's axes."""
        if self.identity:
            return v
        x, y, z = (self.rotation @ np.asarray(v, dtype=float)).tolist()
        return (x, y, z)

    def rotate_covariance(self, covariance: tuple[float, ...]) -> tuple[float, ...]:
        """Return a row-major 3x3 covariance given in sensor axes in the frame's axes."""
        if self.identity:
            return covariance
        c = np.asarray(covariance, dtype=float).reshape(3, 3)
        return tuple((self.rotation @ c @ self.rotation.T).ravel().tolist())

    def orientation(self, world_from_sensor: Quaternion) -> Quaternion:
        """Return world <- frame from world <- sensor."""
        if self.identity:
            return world_from_sensor
        return quaternion_multiply(world_from_sensor, self.sensor_from_frame)


def _finite(name: str, values: tuple[float, ...]) -> None:
    if not all(math.isfinite(v) for v in values):
        raise InputRejectedError(f'IMU {name} is not finite: {values!r}')


def reading_from_sample(
    sample: ImuSample, mounting: Mounting, gyro_bias: Vector3 | None = None
) -> ImuReading:
    """Convert a decoded HiPNUC sample into the published frame.

    The orientation is the sample's quaternion, or, from legacy firmware that sends only
    Euler angles (0xD0), the quaternion of those angles.

    Args:
        sample: decoded frame (SI; quaternion (w, x, y, z)).
        mounting: the sensor's mounting in the published frame.
        gyro_bias: subtracted from the angular rate (sensor axes) [rad/s], if given.

    Returns:
        The reading; fields absent from the sample are None.

    Raises:
        InputRejectedError: a value is NaN/inf, or the quaternion is not (near) unit.
    """
    orientation = None
    if sample.quat is not None:
        w, x, y, z = sample.quat
        orientation = normalize_quaternion((x, y, z, w))
    elif sample.euler is not None:
        _finite('euler angles', sample.euler)
        orientation = quaternion_from_rpy(*sample.euler)
    if orientation is not None:
        orientation = mounting.orientation(orientation)
        # One sign for a given rotation, so consecutive messages do not flip.
        if orientation.w < 0.0:
            orientation = Quaternion(-orientation.x, -orientation.y, -orientation.z, -orientation.w)
    rate = accel = None
    if sample.gyr is not None:
        _finite('angular rate', sample.gyr)
        gyr = sample.gyr
        if gyro_bias is not None:
            gyr = (gyr[0] - gyro_bias[0], gyr[1] - gyro_bias[1], gyr[2] - gyro_bias[2])
        rate = mounting.rotate_vector(gyr)
    if sample.acc is not None:
        _finite('acceleration', sample.acc)
        accel = mounting.rotate_vector(sample.acc)
    return ImuReading(orientation, rate, accel)
