"""Actuators: the shared :class:`Actuator` base and the MIT-mode base.

Each motor family's joint types are in ``rm_base.motors.<family>.actuator``; the joint
``type`` of a robot config finds its class through the registry
(:func:`rm_base.motors.actuator_class`).
"""

from rm_base.hardware.actuators.base import (
    Actuator,
    Defaults,
    Feedback,
    HoldReason,
    JointCommand,
)
from rm_base.hardware.actuators.mit import MitActuator
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
    'MODE_EFFORT',
    'MODE_MIT',
    'MODE_OFF',
    'MODE_POSITION',
    'MODE_VELOCITY',
    'Actuator',
    'Defaults',
    'Feedback',
    'HoldReason',
    'JointCommand',
    'JointState',
    'MitActuator',
    'Mode',
]
