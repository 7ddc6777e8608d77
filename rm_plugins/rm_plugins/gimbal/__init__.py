"""Yaw/pitch gimbal plugin stabilised by its IMU (``rm_plugins/StandGimbal``)."""

from rm_plugins.gimbal.config import AxisConfig, GimbalConfig, read_config
from rm_plugins.gimbal.control import (
    AxisLoop,
    AxisOutput,
    PlanarPose,
    Smoother,
    clamp,
    sight_rates,
)
from rm_plugins.gimbal.plugin import GimbalMode, Measurement, StandGimbal

__all__ = [
    'AxisConfig',
    'AxisLoop',
    'AxisOutput',
    'GimbalConfig',
    'GimbalMode',
    'Measurement',
    'PlanarPose',
    'Smoother',
    'StandGimbal',
    'clamp',
    'read_config',
    'sight_rates',
]
