"""How far a simulated robot's world slipped behind the wall clock during a measurement.

A real-time simulated world starved of CPU lets its time slip: ``<node>: simulator`` on
/diagnostics (``rm_sim: simulator`` from rm_sim's process, ``can_bridge: simulator`` from a
bridge that runs the world itself) has ``slipped [s]``, a running total. A step measured
on the wall clock then looks slower than the simulated joint is. A real robot has no
such status, and then nothing is waited for.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

_KEY = 'slipped [s]'
_REPORT_WAIT_S = 2.5  # the bridge reports at 1 Hz; a report after this long is not coming
# The first report also waits for discovery of the simulator's node: a new process
# regularly needs 2-2.5 s for it (rm_bringup.cli.ros_node.DISCOVERY_TIMEOUT_S).
_FIRST_REPORT_WAIT_S = 6.0


def slipped_s(msg: Any) -> float | None:
    """The simulator's slipped time [s] in one DiagnosticArray, or None if it has none."""
    for status in msg.status:
        if status.name.endswith(': simulator'):
            for pair in status.values:
                if pair.key == _KEY:
                    try:
                        return float(pair.value)
                    except ValueError:
                        return None
    return None


class SlipWatch:
    """/diagnostics' slipped time, from before a measurement to after it.

    Args:
        node: subscribes /diagnostics.
        spin: spins the node's executor once (about 50 ms at most).
        clock: monotonic [s].
    """

    def __init__(self, node: Any, spin: Callable[[], None],
                 clock: Callable[[], float] = time.monotonic) -> None:
        from diagnostic_msgs.msg import DiagnosticArray

        self._spin, self._clock = spin, clock
        self._last: tuple[float, float] | None = None  # (receipt [s], slipped [s])
        node.create_subscription(DiagnosticArray, '/diagnostics', self.on_report, 10)

    def on_report(self, msg: Any) -> None:
        """Take one /diagnostics message."""
        value = slipped_s(msg)
        if value is not None:
            self._last = (self._clock(), value)

    def start(self, simulated: bool) -> float | None:
        """The slipped time now, or None without a report.

        Args:
            simulated: whether the robot runs on a simulator: then a first report is
                waited for; else none is.
        """
        end = self._clock() + _FIRST_REPORT_WAIT_S
        while simulated and self._last is None and self._clock() < end:
            self._spin()
        return None if self._last is None else self._last[1]

    def since(self, before: float | None) -> float | None:
        """How much more slipped since ``before`` (:meth:`start`), from a report after now.

        None when start() had no report. Without a report after now within the wait, the
        last one tells what it can.
        """
        if before is None:
            return None
        now = self._clock()
        end = now + _REPORT_WAIT_S
        while self._clock() < end and (self._last is None or self._last[0] <= now):
            self._spin()
        assert self._last is not None  # start() saw one
        return self._last[1] - before
