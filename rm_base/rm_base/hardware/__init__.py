"""The CAN hardware layer: device protocols, buses, actuators, command groups, scheduler.

No rclpy here. ``rm_base.hardware.protocols`` is the pure bytes <-> values layer.
"""

from rm_base.hardware.errors import (
    BusError,
    BusUnavailableError,
    ChecksumError,
    CommandRejectedError,
    FrameLengthError,
    HardwareConfigError,
    HardwareError,
    ProtocolError,
    ValueRangeError,
)

__all__ = [
    'BusError',
    'BusUnavailableError',
    'ChecksumError',
    'CommandRejectedError',
    'FrameLengthError',
    'HardwareConfigError',
    'HardwareError',
    'ProtocolError',
    'ValueRangeError',
]
