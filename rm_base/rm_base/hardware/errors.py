"""Errors of the CAN hardware layer and its device protocols.

The tree, rooted at :class:`rm_base.errors.RmError`::

    HardwareError
    ├── HardwareConfigError (also ConfigError)    bad bus/joint config, id collision
    ├── ProtocolError (also InputRejectedError)   bytes or values a device protocol refuses
    │   ├── FrameLengthError                       wrong number of bytes
    │   ├── ChecksumError                          CRC or check nibble does not match
    │   └── ValueRangeError                        value outside what the frame can carry
    ├── CommandRejectedError (also InputRejectedError)   NaN target, unknown joint or mode
    └── BusError                                   a CAN bus could not be used

Errors raised by python-can are re-raised as :class:`BusError` ``from`` the original.
"""

from rm_base.errors import ConfigError, InputRejectedError, RmError


class HardwareError(RmError):
    """Base of every error raised on purpose by ``rm_base.hardware``."""


class HardwareConfigError(HardwareError, ConfigError):
    """A bus, joint or protocol configuration is invalid.

    Example: a joint names the motor type ``m3509``, two motors share a DJI command slot,
    or a GM6020 voltage limit above 30000 is configured.
    """


class ProtocolError(HardwareError, InputRejectedError):
    """Bytes or values that a device protocol cannot encode or decode.

    Example: a feedback frame with 7 bytes where 8 are required.
    """


class FrameLengthError(ProtocolError):
    """A frame or payload has the wrong number of bytes.

    Example: a DBUS frame of 17 bytes, a DJI command with five slots.
    """


class ChecksumError(ProtocolError):
    """A frame's CRC or check value does not match its contents.

    Example: a HiPNUC frame with a flipped payload bit, a Piper MIT frame whose XOR nibble
    is wrong.
    """


class ValueRangeError(ProtocolError):
    """A value is NaN, infinite, or outside the range the frame can represent.

    Example: a DJI raw current of 40000, a DBUS channel of 1700, an ESC id of 9.
    """


class CommandRejectedError(HardwareError, InputRejectedError):
    """A joint command was refused and did not reach a motor.

    Example: ``set_command('yaw', MODE_EFFORT, effort=float('nan'))`` or an unknown joint.
    """


class BusError(HardwareError):
    """A CAN bus could not be opened or used.

    Example: ``can0`` does not exist, or the USB adapter was unplugged.
    """
