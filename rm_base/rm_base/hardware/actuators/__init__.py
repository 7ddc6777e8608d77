"""Actuators: one class per joint type on the shared :class:`Actuator` base.

The joint ``type`` of a robot config finds its class through the motor family registry
(:func:`rm_base.motors.actuator_class`), which also lists the families' own classes.
"""

from rm_base.hardware.actuators.base import (
    Actuator,
    Defaults,
    Feedback,
    HoldReason,
    JointCommand,
)
from rm_base.hardware.actuators.dji import (
    M2006,
    M3508,
    DjiActuator,
    Gm6020Current,
    Gm6020Voltage,
)
from rm_base.hardware.actuators.mit import (
    Cheetah,
    Damiao,
    Dm4310,
    Dm4340,
    Dm8009,
    Dm10010L,
    MitActuator,
)
from rm_base.hardware.actuators.piper import PiperJoint
from rm_base.joints import (
    MODE_EFFORT,
    MODE_MIT,
    MODE_OFF,
    MODE_POSITION,
    MODE_VELOCITY,
    JointState,
    Mode,
)

__all__ = [
    'M2006',
    'M3508',
    'MODE_EFFORT',
    'MODE_MIT',
    'MODE_OFF',
    'MODE_POSITION',
    'MODE_VELOCITY',
    'Actuator',
    'Cheetah',
    'Damiao',
    'Defaults',
    'DjiActuator',
    'Dm4310',
    'Dm4340',
    'Dm8009',
    'Dm10010L',
    'Feedback',
    'Gm6020Current',
    'Gm6020Voltage',
    'HoldReason',
    'JointCommand',
    'JointState',
    'MitActuator',
    'Mode',
    'PiperJoint',
]
