"""Serial devices of the robot: one reader per port, with the device's parser."""

from rm_plugins.serial.device import (
    DeviceLink,
    LinkState,
    SerialSettings,
    decide_link,
    expand_port,
    link_status,
    make_reader,
    read_serial_settings,
)
from rm_plugins.serial.reader import FrameStream, ReaderStats, SerialReader, open_serial

__all__ = [
    'DeviceLink',
    'FrameStream',
    'LinkState',
    'ReaderStats',
    'SerialReader',
    'SerialSettings',
    'decide_link',
    'expand_port',
    'link_status',
    'make_reader',
    'open_serial',
    'read_serial_settings',
]
