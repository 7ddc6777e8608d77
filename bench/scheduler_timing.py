"""Measurement 1: the 1 kHz scheduler's period error and missed deadlines.

The production :class:`rm_base.hardware.scheduler.Scheduler` keeps only a histogram, a
mean and a max of ``|start - deadline|``. For percentiles the bench puts a recorder in
front of its ``_record_start`` hook on the *instance* (nothing in rm_base changes, and the
production path has no extra branch): one ``array.append`` per tick while recording.

Definitions (the scheduler's own):

* period error: ``|start - deadline|`` of a tick, deadlines on an absolute grid [µs];
* missed deadline: a deadline skipped because the previous tick ended after it
  (``skipped_ticks``); the share is ``skipped / (ticks + skipped)``.
"""

from __future__ import annotations

import array
from typing import Any

from bench.stats import summary


class TickRecorder:
    """Records every tick's start error of one Scheduler while :meth:`start`-ed."""

    def __init__(self, scheduler: Any) -> None:
        self._scheduler = scheduler
        self.errors_ns = array.array('q')
        self._stats0 = None

    def start(self) -> None:
        """Clear and start recording (hooks the instance)."""
        self.errors_ns = array.array('q')
        append = self.errors_ns.append
        original = type(self._scheduler)._record_start.__get__(self._scheduler)

        def record(error_ns: int) -> None:
            append(error_ns)
            original(error_ns)

        self._stats0 = self._scheduler.stats()
        self._scheduler._record_start = record

    def stop(self) -> dict[str, Any]:
        """Stop recording (unhook) and return :func:`tick_summary` of the window."""
        self._scheduler.__dict__.pop('_record_start', None)
        stats1 = self._scheduler.stats()
        s0 = self._stats0
        ticks = stats1.ticks - s0.ticks
        skipped = stats1.skipped_ticks - s0.skipped_ticks
        overruns = stats1.overruns - s0.overruns
        return tick_summary(self.errors_ns, ticks=ticks, skipped=skipped, overruns=overruns)


def tick_summary(
    errors_ns: Any, *, ticks: int, skipped: int, overruns: int | None = None
) -> dict[str, Any]:
    """Period error percentiles [µs] and the missed-deadline share [%] of one window."""
    s = summary(abs(e) / 1e3 for e in errors_ns)
    deadlines = ticks + skipped
    return {
        'ticks': ticks,
        'skipped': skipped,
        'overruns': overruns,
        'missed_pct': 100.0 * skipped / deadlines if deadlines else float('nan'),
        'error_us': s,
    }
