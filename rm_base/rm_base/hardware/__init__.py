"""The CAN hardware layer: buses, the actuator base, CanHardware (on rm_base.loop).

No rclpy here. ``rm_base.hardware.protocols`` is the pure bytes <-> values layer of what
is not one motor family's; the families (``rm_base.motors``) bring their own protocol and
joint types. CanHardware turns a config dict into running buses and motors.
"""

from rm_base.hardware.actuators import (
    MODE_EFFORT,
    MODE_MIT,
    MODE_OFF,
    MODE_POSITION,
    MODE_VELOCITY,
    Actuator,
    HoldReason,
    JointCommand,
    JointState,
    Mode,
)
from rm_base.hardware.bus import BusState, BusStats, ManagedBus
from rm_base.hardware.can_hardware import CanHardware
from rm_base.hardware.config import BusConfig, HardwareConfig, JointConfig, SafetyConfig
from rm_base.hardware.errors import (
    BusError,
    ChecksumError,
    CommandRejectedError,
    FrameLengthError,
    HardwareConfigError,
    HardwareError,
    ProtocolError,
    ValueRangeError,
)
from rm_base.hardware.power_stage import PowerLimitStage

__all__ = [
    'MODE_EFFORT',
    'MODE_MIT',
    'MODE_OFF',
    'MODE_POSITION',
    'MODE_VELOCITY',
    'Actuator',
    'BusConfig',
    'BusError',
    'BusState',
    'BusStats',
    'CanHardware',
    'ChecksumError',
    'CommandRejectedError',
    'FrameLengthError',
    'HardwareConfig',
    'HardwareConfigError',
    'HardwareError',
    'HoldReason',
    'JointCommand',
    'JointConfig',
    'JointState',
    'ManagedBus',
    'Mode',
    'PowerLimitStage',
    'ProtocolError',
    'SafetyConfig',
    'ValueRangeError',
]
