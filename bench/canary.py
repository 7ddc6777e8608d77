"""A bare 1 kHz sleeper in a process of its own: the machine's wake-up latency.

Run beside the robot during a measuring window, it sleeps to absolute deadlines exactly
as the CAN scheduler does but shares no GIL with anything, so its period error is what
the operating system (other processes, CPU steal, timer slack) costs a 1 kHz thread at
that moment. The scheduler's error minus the canary's is what the robot process itself
(GIL hand-over between its threads) adds. It also counts the gaps between two of its wake-ups
over 1.5 ms, as the wire measurement counts them between two wheel frames: the share the
machine alone gives a 1 kHz sleeper in that window.

    python -m bench.canary <seconds> [<start>]   # prints one '@@BENCH {json}' line

``start`` (a ``time.time()`` value) lets it be launched ahead of the window it measures:
a Python process starting up is a burst of CPU on a 2-core machine, which would land in
the robot's measured window if the sleeper were launched at its start.
"""

from __future__ import annotations

import array
import sys
import time

from bench.protocol import reply
from bench.scheduler_timing import tick_summary

PERIOD_NS = 1_000_000
GAP_NS = 1_500_000  # as bench.wire_check.GAP_S


def run(seconds: float, start: float | None = None) -> dict:
    """Sleep to 1 kHz deadlines for seconds, from start (wall clock; None: now)."""
    if start is not None:
        time.sleep(max(0.0, start - time.time()))
    clock = time.perf_counter_ns
    errors = array.array('q')
    ticks = skipped = late_gaps = 0
    last = None
    deadline = clock() + PERIOD_NS
    end = deadline + int(seconds * 1e9)
    while deadline < end:
        delay = deadline - clock()
        if delay > 0:
            time.sleep(delay / 1e9)
        start = clock()
        errors.append(start - deadline)
        if last is not None and start - last > GAP_NS:
            late_gaps += 1
        last = start
        ticks += 1
        deadline += PERIOD_NS
        if start > deadline:  # as the scheduler: skip missed deadlines, no burst
            missed = (start - deadline) // PERIOD_NS + 1
            skipped += missed
            deadline += missed * PERIOD_NS
    out = tick_summary(errors, ticks=ticks, skipped=skipped)
    out['late_gap_pct'] = 100.0 * late_gaps / (ticks - 1) if ticks > 1 else float('nan')
    return out


if __name__ == '__main__':
    reply(run(float(sys.argv[1]), float(sys.argv[2]) if len(sys.argv) > 2 else None))
