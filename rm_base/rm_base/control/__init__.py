"""Control maths: PID controllers, tracking differentiator, ramps and filters.

Pure Python on plain floats (no ROS, no I/O, no threads), cheap enough for 1 kHz loops.
Every ``update`` raises ``rm_base.errors.InputRejectedError`` on NaN/inf input or a
non-positive dt, and every config dataclass raises ``rm_base.errors.ConfigError`` on
construction with a bad value.
"""

from rm_base.control.filters import LowPassFilter, MovingAverage
from rm_base.control.incremental_pid import IncrementalPid, IncrementalPidGains
from rm_base.control.pid import Pid, PidGains
from rm_base.control.ramp import RampLimiter, RampLimits, ramp_step
from rm_base.control.tracking_differentiator import TdParams, TrackingDifferentiator, fhan

__all__ = [
    'IncrementalPid',
    'IncrementalPidGains',
    'LowPassFilter',
    'MovingAverage',
    'Pid',
    'PidGains',
    'RampLimiter',
    'RampLimits',
    'TdParams',
    'TrackingDifferentiator',
    'fhan',
    'ramp_step',
]
