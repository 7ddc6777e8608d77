"""The CAN hardware layer: device protocols, buses, actuators, command groups, scheduler.

No rclpy here. ``rm_base.hardware.protocols`` is the pure bytes <-> values layer; the rest
turns a config dict into running buses and motors behind :class:`CanHardware`.
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
from rm_base.hardware.groups import DjiCommandGroup
from rm_base.hardware.power_stage import PowerLimitStage
from rm_base.hardware.scheduler import Scheduler, Stage
from rm_base.hardware.timing import DurationHistogram, DurationSummary, PeriodStats

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
    'DjiCommandGroup',
    'DurationHistogram',
    'DurationSummary',
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
    'PeriodStats',
    'PowerLimitStage',
    'ProtocolError',
    'SafetyConfig',
    'Scheduler',
    'Stage',
    'ValueRangeError',
]
