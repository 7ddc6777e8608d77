"""An ImuReading as sensor_msgs/Imu (REP 145: a covariance of -1 marks a field not given)."""

from __future__ import annotations

from sensor_msgs.msg import Imu

from rm_plugins.imu.conversion import ImuReading

_NS_PER_S = 1_000_000_000

#: Covariance of a field the sample did not carry (REP 145).
NOT_PROVIDED = (-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

Covariance = tuple[float, ...]


def imu_message(
    reading: ImuReading,
    stamp_ns: int,
    frame_id: str,
    covariances: tuple[Covariance, Covariance, Covariance],
) -> Imu:
    """Build the message of one reading.

    Args:
        reading: the sample in the published frame.
        stamp_ns: when the sensor took it, on the node's clock [ns].
        frame_id: header.frame_id.
        covariances: orientation, angular velocity and linear acceleration covariances
            (row-major 3x3), used where the reading has the field.
    """
    msg = Imu()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, _NS_PER_S)
    msg.header.frame_id = frame_id
    orientation_cov, angular_cov, linear_cov = covariances
    if reading.orientation is not None:
        q = reading.orientation
        msg.orientation.x, msg.orientation.y = q.x, q.y
        msg.orientation.z, msg.orientation.w = q.z, q.w
        msg.orientation_covariance = orientation_cov
    else:
        msg.orientation_covariance = NOT_PROVIDED
    if reading.angular_velocity is not None:
        v = msg.angular_velocity
        v.x, v.y, v.z = reading.angular_velocity
        msg.angular_velocity_covariance = angular_cov
    else:
        msg.angular_velocity_covariance = NOT_PROVIDED
    if reading.linear_acceleration is not None:
        a = msg.linear_acceleration
        a.x, a.y, a.z = reading.linear_acceleration
        msg.linear_acceleration_covariance = linear_cov
    else:
        msg.linear_acceleration_covariance = NOT_PROVIDED
    return msg
