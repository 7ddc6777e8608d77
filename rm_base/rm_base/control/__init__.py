"""Control maths: PID, tracking differentiator, ramps, filters, lookup tables, chassis power.

Pure Python on plain floats (no ROS, no I/O, no threads), cheap enough for 1 kHz loops.
Every ``update`` raises ``rm_base.errors.InputRejectedError`` on NaN/inf input or a
non-positive dt, and every config dataclass raises ``rm_base.errors.ConfigError`` on
construction with a bad value.
"""

from rm_base.control.filters import LowPassFilter, MovingAverage
from rm_base.control.incremental_pid import IncrementalPid, IncrementalPidGains
from rm_base.control.lookup import LookupTable
from rm_base.control.pid import Pid, PidGains
from rm_base.control.pid_form import IncrementalPidConfig, PidConfig, build_pid, pid_config
from rm_base.control.power_limit import (
    ChassisPowerModel,
    PowerLimitResult,
    estimate_power,
    fit_power_model,
    limit_power,
    power_limit_scale,
)
from rm_base.control.ramp import RampLimiter, RampLimits, ramp_step
from rm_base.control.tracking_differentiator import TdParams, TrackingDifferentiator, fhan

__all__ = [
    'ChassisPowerModel',
    'IncrementalPid',
    'IncrementalPidConfig',
    'IncrementalPidGains',
    'LookupTable',
    'LowPassFilter',
    'MovingAverage',
    'Pid',
    'PidConfig',
    'PidGains',
    'PowerLimitResult',
    'RampLimiter',
    'RampLimits',
    'TdParams',
    'TrackingDifferentiator',
    'build_pid',
    'estimate_power',
    'fhan',
    'fit_power_model',
    'limit_power',
    'pid_config',
    'power_limit_scale',
    'ramp_step',
]
