"""HiPNUC Hi220 IMU plugin: serial frames -> sensor_msgs/Imu (``rm_plugins/Hi220``)."""

from rm_plugins.imu.conversion import ImuReading, Mounting, reading_from_sample
from rm_plugins.imu.plugin import Hi220, ImuState, expand_port
from rm_plugins.imu.reader import ReaderStats, SerialReader, open_serial

__all__ = [
    'Hi220',
    'ImuReading',
    'ImuState',
    'Mounting',
    'ReaderStats',
    'SerialReader',
    'expand_port',
    'open_serial',
    'reading_from_sample',
]
