"""Simulated CAN interface ``rm_sim`` and motor/robot physics (no rclpy)."""

from rm_base.sim.errors import SimConfigError, SimError, SimLookupError, SimStateError
from rm_base.sim.motor import (
    DJI_ENCODER_COUNTS,
    MOTOR_DEFAULTS,
    DriveMode,
    MotorModel,
    MotorParams,
    MotorType,
    motor_params,
)

__all__ = [
    'DJI_ENCODER_COUNTS',
    'MOTOR_DEFAULTS',
    'DriveMode',
    'MotorModel',
    'MotorParams',
    'MotorType',
    'SimConfigError',
    'SimError',
    'SimLookupError',
    'SimStateError',
    'motor_params',
]
