"""HiPNUC Hi220 IMU plugin: serial frames -> sensor_msgs/Imu (``rm_plugins/Hi220``)."""

from rm_plugins.imu.conversion import ImuReading, Mounting, reading_from_sample
from rm_plugins.imu.plugin import Hi220, ImuState

__all__ = [
    'Hi220',
    'ImuReading',
    'ImuState',
    'Mounting',
    'reading_from_sample',
]
