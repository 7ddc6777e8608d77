"""Measurement 1: the 1 kHz scheduler's period error and missed deadlines.

The production :class:`rm_base.loop.scheduler.Scheduler` keeps only a histogram, a
mean and a max of ``|start - deadline|``. For percentiles the bench observes every tick
(``Scheduler.observe_ticks``): one ``array.append`` per tick while recording.

Definitions (the scheduler's own):

* period error: ``|start - deadline|`` of a tick, deadlines on an absolute grid [µs];
* missed deadline: a tick that ended after the next tick's deadline (``overruns``; the
  next tick then runs at once, late, and periods that passed whole are ``skipped``); the
  share is ``overruns / ticks``. Loops the bench only watches from outside (the bare
  sleeper, an rclpy timer) count the periods with no tick: ``skipped / (ticks + skipped)``;
* tick duration: update + pack + send of one tick [µs], from the tick's start as the
  loop thread times it (``Scheduler.observe_ticks``). On rm_sim a send waits for the
  simulated world's lock, so time the physics thread holds it shows up here.
"""

from __future__ import annotations

import array
import time
from typing import Any

from bench.stats import summary


class TickRecorder:
    """Records every tick's start error of one Scheduler while :meth:`start`-ed."""

    def __init__(self, scheduler: Any) -> None:
        self._scheduler = scheduler
        self.errors_ns = array.array('q')
        self.ticks_ns = array.array('q')
        self._stats0 = None
        self._t0_ns = 0

    def start(self) -> None:
        """Clear and start recording."""
        self.errors_ns = array.array('q')
        self.ticks_ns = array.array('q')
        append_error, append_tick = self.errors_ns.append, self.ticks_ns.append

        def record(error_ns: int, tick_ns: int) -> None:
            append_error(error_ns)
            append_tick(tick_ns)

        self._stats0 = self._scheduler.stats()
        self._scheduler.observe_ticks(record)
        self._t0_ns = time.perf_counter_ns()

    def stop(self) -> dict[str, Any]:
        """Stop recording (unhook) and return :func:`tick_summary` of the window.

        Besides the summary: ``elapsed_s``, the recorder's own window, and ``achieved_hz``,
        the ticks counted in it over its length. A window measured around it (the CPU
        snapshots) is longer by the time its snapshots take, and ticks over that would
        come out short of the loop's real rate.
        """
        elapsed_ns = time.perf_counter_ns() - self._t0_ns
        self._scheduler.observe_ticks(None)
        stats1 = self._scheduler.stats()
        s0 = self._stats0
        ticks = stats1.ticks - s0.ticks
        skipped = stats1.skipped_ticks - s0.skipped_ticks
        overruns = stats1.overruns - s0.overruns
        out = tick_summary(self.errors_ns, ticks=ticks, skipped=skipped, overruns=overruns)
        out['tick_us'] = summary(t / 1e3 for t in self.ticks_ns)
        out['elapsed_s'] = elapsed_ns / 1e9
        out['achieved_hz'] = ticks * 1e9 / elapsed_ns if elapsed_ns > 0 else float('nan')
        return out


def tick_summary(
    errors_ns: Any, *, ticks: int, skipped: int, overruns: int | None = None
) -> dict[str, Any]:
    """Period error percentiles [µs] and the missed-deadline share [%] of one window."""
    s = summary(abs(e) / 1e3 for e in errors_ns)
    if overruns is None:
        missed, deadlines = skipped, ticks + skipped
    else:
        missed, deadlines = overruns, ticks
    return {
        'ticks': ticks,
        'skipped': skipped,
        'overruns': overruns,
        'missed_pct': 100.0 * missed / deadlines if deadlines else float('nan'),
        'error_us': s,
    }
