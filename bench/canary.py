"""A bare 1 kHz sleeper in a process of its own: the machine's wake-up latency.

Run beside the robot during a measuring window, it sleeps to absolute deadlines exactly
as the CAN scheduler does but shares no GIL with anything, so its period error is what
the operating system (other processes, CPU steal, timer slack) costs a 1 kHz thread at
that moment. The scheduler's error minus the canary's is what the robot process itself
(GIL hand-over between its threads) adds.

    python -m bench.canary <seconds>    # prints one '@@BENCH {json}' line
"""

from __future__ import annotations

import array
import sys
import time

from bench.protocol import reply
from bench.scheduler_timing import tick_summary

PERIOD_NS = 1_000_000


def run(seconds: float) -> dict:
    clock = time.perf_counter_ns
    errors = array.array('q')
    ticks = skipped = 0
    deadline = clock() + PERIOD_NS
    end = deadline + int(seconds * 1e9)
    while deadline < end:
        delay = deadline - clock()
        if delay > 0:
            time.sleep(delay / 1e9)
        start = clock()
        errors.append(start - deadline)
        ticks += 1
        deadline += PERIOD_NS
        if start > deadline:  # as the scheduler: skip missed deadlines, no burst
            missed = (start - deadline) // PERIOD_NS + 1
            skipped += missed
            deadline += missed * PERIOD_NS
    return tick_summary(errors, ticks=ticks, skipped=skipped)


if __name__ == '__main__':
    reply(run(float(sys.argv[1])))
