"""PluginTask: one plugin as a stage of the control loop, run when it is due.

A plugin runs at its own rate on the loop's ticks (the first tick at or after each
deadline; a late tick moves the schedule on instead of bursting to catch up), and also at
the next tick after a new command arrived (``run_on_command``), so a command reaches the
motors within a loop period, not a plugin period. A run for a new command comes at least
a quarter of the plugin's period (at most 2 ms) after its last run, scheduled or not, so a
command flood cannot run a plugin on every tick, nor a command add a run right beside a
scheduled one (docs/PERFORMANCE.md, "Plugins that would not fit wait a tick").

Tasks of one loop share a :class:`TickInputs`: the plugins' clock is read and the local
joint view refreshed at most once per tick, and only on ticks where a plugin runs.

A run that would not fit before the tick's deadline waits one tick: given the loop's
``time_left`` (the real-time loop's; a stepped loop has none), a plugin whose long run
(moving mean plus twice the moving mean deviation of its own runs, as TCP estimates a
round trip) plus the time the loop still needs after the plugins
(``RESERVE_NS``) exceeds what is left of the period runs at the next tick instead, and
then unconditionally. So runs that fall due together (several commands arriving at
once, or scheduled runs) spread over two ticks rather than push the tick past its
deadline; no plugin waits more than one tick. A run for a new command moves too: had it
run, the frames of this tick would have gone out late and the next tick with them, so
its command reaches the motors about as soon either way. Lockstep runs never wait.

The loop never waits for a plugin: ``enable``/``disable`` (ROS services, executor thread)
take the plugin's lock; the loop only tries it, and runs the plugin at a later tick if it
is held. No rclpy here.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from rm_base.loop.data import COMMANDS, JOINT_STATES, JOINT_TARGETS, PUBLISHED
from rm_base.plugin.base import PluginBase

_NS_PER_S = 1_000_000_000
# Shortest time between two runs when new commands arrive: a quarter period, at most this.
_MAX_GAP_NS = 2_000_000
#: What a tick needs after the plugins (actuator updates, power limit, pack, send) [ns].
RESERVE_NS = 200_000
# Weights of the newest run in the moving mean and mean deviation of a plugin's run time.
_MEAN_WEIGHT = 0.125
_DEV_WEIGHT = 0.25


class TickInputs:
    """What the plugins of one loop read once per tick.

    Args:
        now: the plugins' clock (an rclpy Time: the node clock's ``now``).
        refresh: fills the joint-state view from the actuators (LocalJointIO.refresh),
            given the tick's time on the plugins' clock [ns]; None with DDS joint I/O.
        time_left: ns left until the running tick's deadline, None outside a real-time
            tick (``Scheduler.time_left_ns``); None: runs never wait for a later tick.
    """

    def __init__(
        self,
        now: Callable[[], Any],
        refresh: Callable[[int], None] | None = None,
        time_left: Callable[[], float | None] | None = None,
    ) -> None:
        self._now = now
        self._refresh = refresh
        self.time_left = time_left
        self._tick_ns: int | None = None
        self._time: Any = None

    def at(self, tick_ns: int) -> Any:
        """The plugins' time for the loop tick tick_ns, the joint view refreshed for it."""
        if tick_ns != self._tick_ns:
            self._tick_ns = tick_ns
            self._time = self._now()
            if self._refresh is not None:
                self._refresh(self._time.nanoseconds)
        return self._time


class PluginTask:
    """Runs one plugin in the loop (a ``Stage`` of :class:`~rm_base.hardware.Scheduler`).

    Args:
        plugin: an initialised plugin.
        inputs: the loop's shared per-tick inputs.
        phase_ns: how long after enable the first scheduled run comes [ns]; the host
            gives each plugin another tick, so that plugins of similar rates do not all
            run in one tick and overrun it (firmware schedulers offset their tasks alike).
        targets_datum: what its joint targets are in the loop's order: the targets the
            actuators read, or (over DDS) what the ROS edge publishes.

    Attributes:
        name: stage name, ``plugin <instance name>``.
        ticks: runs so far (new-command runs included).
        command_runs: of those, runs for a new command before the plugin's deadline.
        skipped: the plugin's deadlines that passed without a run (late loop ticks, or
            the plugin's lock held by enable/disable).
        deferred: runs moved to the next tick because they would not fit in this one.
        cost_ns: a long run of the plugin: moving mean + 2 moving mean deviations [ns].
        errors: failures outside ``plugin.run`` (the clock, the joint view); each
            disables the plugin (zero output), with the error as its reason.
    """

    def __init__(
        self,
        plugin: PluginBase,
        inputs: TickInputs,
        phase_ns: int = 0,
        targets_datum: str = JOINT_TARGETS,
    ) -> None:
        self.plugin = plugin
        self.name = f'plugin {plugin.name}'
        # after the feedback, the commands and its devices; its state goes to the ROS edge
        self.reads = (JOINT_STATES, COMMANDS, *plugin.loop_reads)
        self.writes = (targets_datum, PUBLISHED) if plugin.joints else (PUBLISHED,)
        self.period_ns = round(_NS_PER_S / plugin.rate)
        self.lock = threading.Lock()
        self.ticks = 0
        self.command_runs = 0
        self.skipped = 0
        self.deferred = 0
        self.errors = 0
        self.cost_ns = 0.0
        self._mean_ns = 0.0
        self._dev_ns = 0.0
        self._waiting = False  # deferred at the previous tick: runs now whatever is left
        self._inputs = inputs
        self._min_gap_ns = min(self.period_ns // 4, _MAX_GAP_NS)
        self.phase_ns = phase_ns % self.period_ns
        self._next_ns: int | None = None
        self._last_ns: int | None = None
        self._new_command = False
        plugin.command_listener = self._on_command

    def _on_command(self) -> None:
        # Executor thread: a flag the loop reads at its next tick.
        self._new_command = True

    def __call__(self, now_ns: int, dt: float) -> bool:
        """Run the plugin if it is due at loop time now_ns; return whether it ran."""
        plugin = self.plugin
        if not plugin.enabled:
            self._next_ns = None
            self._waiting = False
            return False
        next_ns = self._next_ns
        if next_ns is None:
            next_ns = self._next_ns = now_ns + self.phase_ns
        due = now_ns >= next_ns
        for_command = (
            not due
            and self._new_command
            and (self._last_ns is None or now_ns - self._last_ns >= self._min_gap_ns)
        )
        if not (due or for_command):
            return False
        if not self._waiting and not self._fits():
            self._waiting = True
            self.deferred += 1
            return False
        if not self.lock.acquire(blocking=False):
            return False
        try:
            self._new_command = False
            try:
                now = self._inputs.at(now_ns)
            except Exception as err:  # outside plugin.run (which never raises): turn it off
                self.errors += 1
                plugin.disable(f'loop failed: {type(err).__name__}: {err}')
                return True
            started = time.perf_counter_ns()
            plugin.run(now)
            self._learn(time.perf_counter_ns() - started)
        finally:
            self.lock.release()
        self._waiting = False
        self.ticks += 1
        self._last_ns = now_ns
        if for_command:
            self.command_runs += 1
            self._next_ns = now_ns + self.period_ns
        else:
            next_ns += self.period_ns
            if next_ns <= now_ns:
                missed = (now_ns - next_ns) // self.period_ns + 1
                self.skipped += missed
                next_ns += missed * self.period_ns
            self._next_ns = next_ns
        return True

    def _learn(self, run_ns: int) -> None:
        error = run_ns - self._mean_ns
        self._mean_ns += error * _MEAN_WEIGHT
        self._dev_ns += (abs(error) - self._dev_ns) * _DEV_WEIGHT
        self.cost_ns = self._mean_ns + 2.0 * self._dev_ns

    def _fits(self) -> bool:
        """Whether a long run still ends before the tick's deadline (with the reserve)."""
        time_left = self._inputs.time_left
        left = time_left() if time_left is not None else None
        return left is None or left - self.cost_ns >= RESERVE_NS

    def enable(self) -> bool:
        """Enable the plugin between two of its runs; return False if it already was."""
        with self.lock:
            return self.plugin.enable()

    def disable(self, reason: str = 'disabled') -> None:
        """Disable the plugin between two of its runs (zero output first)."""
        with self.lock:
            self.plugin.disable(reason)
