"""Yaw/pitch gimbal plugin stabilised by its IMU (``rm_plugins/StandGimbal``)."""

from rm_plugins.gimbal.commands import GimbalMode, GimbalRequest, parse_gimbal_cmd
from rm_plugins.gimbal.config import AxisConfig, GimbalConfig, read_config
from rm_plugins.gimbal.control import (
    AxisLoop,
    AxisOutput,
    PlanarPose,
    Smoother,
    clamp,
    sight_rates,
)
from rm_plugins.gimbal.plugin import Measurement, StandGimbal

__all__ = [
    'AxisConfig',
    'AxisLoop',
    'AxisOutput',
    'GimbalConfig',
    'GimbalMode',
    'GimbalRequest',
    'Measurement',
    'PlanarPose',
    'Smoother',
    'StandGimbal',
    'clamp',
    'parse_gimbal_cmd',
    'read_config',
    'sight_rates',
]
