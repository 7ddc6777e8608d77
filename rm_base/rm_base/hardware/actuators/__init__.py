"""Actuators: one class per motor family on the shared :class:`Actuator` base.

:data:`ACTUATOR_TYPES` maps the ``type`` of a joint config to its class; adding a motor
family means adding one class here.
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

#: Joint ``type`` -> actuator class.
ACTUATOR_TYPES: dict[str, type[Actuator]] = {
    cls.type_name: cls
    for cls in (
        M3508,
        M2006,
        Gm6020Voltage,
        Gm6020Current,
        Damiao,
        Dm4310,
        Dm4340,
        Dm8009,
        Dm10010L,
        Cheetah,
        PiperJoint,
    )
}

__all__ = [
    'ACTUATOR_TYPES',
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
