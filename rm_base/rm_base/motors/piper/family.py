"""The piper family as the motor registry sees it (rm_base/motors/registry.py)."""

from __future__ import annotations

from rm_base.motors.family import MotorFamily
from rm_base.motors.piper.actuator import PiperJoint

FAMILY = MotorFamily(name='piper', actuators=(PiperJoint,))
