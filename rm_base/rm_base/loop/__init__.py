"""The robot's one control loop: its components, their derived order, its timing.

The loop owns the tick: the hardware, the command inbox, the plugins, the power limits and
the ROS edge join it as components that declare what they read and write
(:mod:`rm_base.loop.data`); :mod:`rm_base.loop.order` derives the order from those
declarations. Below the hardware: it opens no bus (frames are python-can messages the
hardware hands it) and uses no ROS.
"""

from rm_base.loop.errors import LoopConfigError
from rm_base.loop.scheduler import Scheduler, Stage
from rm_base.loop.timing import DurationHistogram, DurationSummary, PeriodStats

__all__ = [
    'DurationHistogram',
    'DurationSummary',
    'LoopConfigError',
    'PeriodStats',
    'Scheduler',
    'Stage',
]
