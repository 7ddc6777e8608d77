"""AgileX Piper arm joints driven in MIT mode (no simulated model)."""

from __future__ import annotations

from rm_base.hardware.actuators.piper import PiperJoint
from rm_base.motors.family import MotorFamily

FAMILY = MotorFamily(name='piper', actuators=(PiperJoint,))
