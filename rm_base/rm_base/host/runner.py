"""PluginRunner: one thread per plugin calling run() at the plugin's rate.

Why a thread per plugin and not rclpy timers: a 1 kHz rclpy timer on the default executor
costs ~46 % of a core for an empty callback (docs: ROS_WHEELS.md), and timers sharing one
executor delay each other, so a slow plugin would stall the rest. Each runner sleeps to
absolute deadlines on ``time.perf_counter_ns`` (no drift) and counts overruns; a tick that
ends more than a period late skips the missed deadlines instead of bursting to catch up
(a control loop wants a steady dt, not a volley of ticks with dt near zero).

A new command (``PluginBase.command_listener``, when the plugin's ``run_on_command`` is
set) wakes the runner to run at once instead of at the next deadline, and the schedule
goes on a period after that run: the command reaches the motors up to a period sooner
(5 ms at 200 Hz). Runs stay at least a quarter period (at most 2 ms) apart, so a command
flood cannot raise the rate above four times the plugin's own (500 Hz for slow plugins),
and no run sees a dt below that. Off by default: each extra run costs a tick's CPU, which
a 2-core machine running the whole robot in one interpreter does not have to spare.

One ``threading.Condition`` per runner serialises ``run()`` with ``enable()`` and
``disable()`` (which arrive on the ROS executor thread through services), and wakes a
disabled runner when it is enabled again. No rclpy here.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from rm_base.plugin.base import PluginBase

_NS_PER_S = 1_000_000_000
# Longest single sleep, so stop() is honoured within this time even at low rates [ns].
_MAX_SLEEP_NS = 50_000_000
# Shortest time between two runs when a command wakes the runner: a quarter period, at
# most this [ns].
_MAX_GAP_NS = 2_000_000


class PluginRunner:
    """Runs one plugin at its own rate in a dedicated thread.

    Args:
        plugin: an initialised plugin.
        now: returns the current time for ``run(now)`` (the node clock's ``now``).
        on_error: called from the runner thread if something outside ``plugin.run``
            raises (``plugin.run`` itself never raises); returns True to keep running.

    Attributes:
        ticks: run() calls since start (extra runs included).
        extra_runs: of those, runs at once for a new command.
        overruns: ticks that ended after the next deadline.
        skipped: deadlines skipped because a tick ended more than a period late.
    """

    def __init__(
        self,
        plugin: PluginBase,
        now: Callable[[], Any],
        *,
        on_error: Callable[[PluginRunner, Exception], bool] | None = None,
    ) -> None:
        self.plugin = plugin
        self.period_ns = round(_NS_PER_S / plugin.rate)
        self.ticks = 0
        self.extra_runs = 0
        self.overruns = 0
        self.skipped = 0
        self._now = now
        self._wake = threading.Event()
        self._min_gap_ns = min(self.period_ns // 4, _MAX_GAP_NS)
        plugin.command_listener = self._wake.set
        self._on_error = on_error
        self._cond = threading.Condition()
        self._stopping = False
        self._thread = threading.Thread(
            target=self._loop, name=f'plugin:{plugin.name}', daemon=True
        )

    @property
    def name(self) -> str:
        """The plugin's instance name."""
        return self.plugin.name

    @property
    def alive(self) -> bool:
        """Whether the runner thread is running."""
        return self._thread.is_alive()

    def start(self) -> None:
        """Start the thread (it idles while the plugin is disabled)."""
        self._thread.start()

    def stop(self, timeout: float = 2.0) -> bool:
        """Stop after the current tick; return False if the thread did not end in timeout [s]."""
        with self._cond:
            self._stopping = True
            self._cond.notify_all()
        self._wake.set()
        if self._thread.is_alive():
            self._thread.join(timeout)
        return not self._thread.is_alive()

    def enable(self) -> bool:
        """Enable the plugin between two ticks; return False if it already was."""
        with self._cond:
            changed = self.plugin.enable()
            self._cond.notify_all()
            return changed

    def disable(self, reason: str = 'disabled') -> None:
        """Disable the plugin between two ticks (zero output first)."""
        with self._cond:
            self.plugin.disable(reason)

    def _loop(self) -> None:
        next_ns: int | None = None
        last_ns: int | None = None
        extra = False  # this run is one at once for a new command, between deadlines
        while True:
            ran = False
            try:
                with self._cond:
                    while not self._stopping and not self.plugin.enabled:
                        next_ns = last_ns = None
                        extra = False
                        self._cond.wait()
                    if self._stopping:
                        return
                    start_ns = time.perf_counter_ns()
                    if next_ns is None:
                        next_ns = start_ns
                    dt = (start_ns - last_ns if last_ns is not None else self.period_ns) / _NS_PER_S
                    last_ns = start_ns
                    self.plugin.run(self._now(), dt)
                    ran = True
            except Exception as err:
                if self._on_error is None or not self._on_error(self, err):
                    return
                if next_ns is None:
                    continue
            # A failed tick keeps the schedule (no busy loop) but is not counted.
            self.ticks += ran
            if extra:
                self.extra_runs += ran
                next_ns = start_ns + self.period_ns
            else:
                next_ns += self.period_ns
                late_ns = time.perf_counter_ns() - next_ns
                if late_ns > 0:
                    self.overruns += 1
                    if late_ns >= self.period_ns:
                        missed = late_ns // self.period_ns
                        self.skipped += missed
                        next_ns += missed * self.period_ns
                    continue
            # a command that came during the run is in it already
            self._wake.clear()
            extra = self._sleep_until(next_ns, wakeable=True)
            if extra:
                self._sleep_until(start_ns + self._min_gap_ns)

    def _sleep_until(self, deadline_ns: int, *, wakeable: bool = False) -> bool:
        """Sleep to deadline_ns; return True if a new command woke the runner first."""
        while not self._stopping:
            remaining_ns = deadline_ns - time.perf_counter_ns()
            if remaining_ns <= 0:
                return False
            timeout = min(remaining_ns, _MAX_SLEEP_NS) / _NS_PER_S
            if not wakeable:
                time.sleep(timeout)
            elif self._wake.wait(timeout):
                self._wake.clear()
                return not self._stopping
        return False
