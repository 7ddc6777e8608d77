"""The control scheduler: update every actuator, then pack every frame, then send.

One dedicated thread sleeps to absolute deadlines on ``time.perf_counter_ns`` (1 kHz by
default) and runs :meth:`Scheduler.tick`; tests call ``tick(now_ns)`` themselves, with no
thread, for deterministic steps. Each tick is strictly three phases:

1. ``update(now_ns, dt)`` on every actuator (control laws, safety),
2. ``pack_command()`` on every packer (actuators with their own frame, command groups),
3. ``send(msg)`` of every packed frame, each through the send function (bus) paired with
   its packer.

Missed deadlines are counted as overruns and skipped, never caught up in a burst. Period
statistics are cheap: count, running max, mean and a fixed histogram of the start-time
error. An exception escaping a tick goes to ``on_error(exc)``, which decides whether to go
on (as python-can's ``ThreadBasedCyclicSendTask``); without a hook the loop stops.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
from collections.abc import Callable, Sequence
from typing import Protocol

import can

from rm_base.hardware.errors import HardwareConfigError

_log = logging.getLogger(__name__)

#: Upper edges of the period-error histogram buckets [µs]; the last bucket is open.
HISTOGRAM_EDGES_US = (10, 50, 100, 200, 500, 1000, 2000, 5000)


class Updatable(Protocol):
    """Anything updated once per tick (an actuator)."""

    def update(self, now_ns: int, dt: float) -> None:
        """Compute this tick's output."""


class Packer(Protocol):
    """Anything that packs a frame per tick (an actuator or a command group)."""

    def pack_command(self) -> can.Message | None:
        """Return this tick's frame, or None."""


@dataclasses.dataclass(frozen=True)
class PeriodStats:
    """Timing of the scheduler loop.

    Attributes:
        period_ns: nominal period [ns].
        ticks: ticks run.
        overruns: deadlines missed (a tick ended after the next deadline).
        skipped_ticks: deadlines skipped because of overruns.
        max_error_us: largest |start - deadline| seen [µs].
        mean_error_us: mean |start - deadline| [µs].
        histogram: counts per bucket of |start - deadline|; bucket i holds errors below
            ``HISTOGRAM_EDGES_US[i]`` µs, the last one the rest.
        max_tick_us: longest tick (update + pack + send) [µs].
        errors: exceptions passed to on_error.
    """

    period_ns: int
    ticks: int
    overruns: int
    skipped_ticks: int
    max_error_us: float
    mean_error_us: float
    histogram: tuple[int, ...]
    max_tick_us: float
    errors: int


class Scheduler:
    """Runs update -> pack -> send for a set of actuators and packers at a fixed rate."""

    def __init__(
        self,
        actuators: Sequence[Updatable],
        packers: Sequence[tuple[Packer, Callable[[can.Message], object]]],
        *,
        rate_hz: float = 1000.0,
        on_error: Callable[[Exception], bool] | None = None,
        clock_ns: Callable[[], int] = time.perf_counter_ns,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        """Create a stopped scheduler.

        Args:
            actuators: updated first, in this order.
            packers: ``(packer, send)`` pairs, packed second in this order; each frame is
                then sent, in the same order, with its pair's ``send`` (a bus's send,
                which must not raise for bus trouble).
            rate_hz: tick rate [Hz].
            on_error: called with an exception escaping a tick; return True to go on.
                None stops the loop at the first exception (it is logged).
            clock_ns: monotonic clock [ns].
            sleep: sleep function [s] (tests may replace it).

        Raises:
            HardwareConfigError: rate_hz not positive.
        """
        if not rate_hz > 0:
            raise HardwareConfigError(f'scheduler rate must be > 0 Hz, got {rate_hz!r}')
        self._actuators = tuple(actuators)
        self._packers = tuple(packers)
        self.period_ns = round(1e9 / rate_hz)
        self._period_s = self.period_ns / 1e9
        self.on_error = on_error
        self._clock_ns = clock_ns
        self._sleep = sleep
        self._last_tick_ns: int | None = None
        self._frames: list[tuple[Callable[[can.Message], object], can.Message]] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._final: Callable[[], None] | None = None
        # statistics
        self._ticks = 0
        self._overruns = 0
        self._skipped = 0
        self._errors = 0
        self._max_error_ns = 0
        self._sum_error_ns = 0
        self._timed = 0
        self._max_tick_ns = 0
        self._histogram = [0] * (len(HISTOGRAM_EDGES_US) + 1)
        self._edges_ns = tuple(e * 1000 for e in HISTOGRAM_EDGES_US)

    # --- one cycle ---
    def tick(self, now_ns: int) -> int:
        """Run one cycle: update all, then pack all, then send all.

        Args:
            now_ns: the tick time [ns] on the actuators' clock.

        Returns:
            Number of frames handed to ``send``.
        """
        last = self._last_tick_ns
        dt = (now_ns - last) / 1e9 if last is not None and now_ns > last else self._period_s
        self._last_tick_ns = now_ns
        for actuator in self._actuators:
            actuator.update(now_ns, dt)
        frames = self._frames
        frames.clear()
        for packer, send in self._packers:
            msg = packer.pack_command()
            if msg is not None:
                frames.append((send, msg))
        for send, msg in frames:
            send(msg)
        self._ticks += 1
        return len(frames)

    # --- the thread ---
    @property
    def running(self) -> bool:
        """Whether the scheduler thread is alive."""
        return self._thread is not None and self._thread.is_alive()

    def start(self, final: Callable[[], None] | None = None) -> None:
        """Start the thread. Idempotent while running.

        Args:
            final: called on the scheduler thread when the loop ends for any reason (the
                facade sends its zero frames there).
        """
        if self.running:
            return
        self._final = final
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name='can-scheduler', daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop the thread and wait for it (including ``final``). Idempotent."""
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout_s)
            if thread.is_alive():
                _log.error('scheduler thread did not stop within %.1f s', timeout_s)

    def _run(self) -> None:
        clock = self._clock_ns
        period = self.period_ns
        deadline = clock()
        try:
            while not self._stop.is_set():
                start = clock()
                self._record_start(start - deadline)
                try:
                    self.tick(start)
                except Exception as exc:
                    self._errors += 1
                    _log.exception('scheduler tick failed')
                    if self.on_error is None or not self.on_error(exc):
                        _log.error('scheduler stopped after an error')
                        break
                end = clock()
                self._max_tick_ns = max(self._max_tick_ns, end - start)
                deadline += period
                if end > deadline:
                    self._overruns += 1
                    missed = (end - deadline) // period + 1
                    self._skipped += missed
                    deadline += missed * period
                delay_ns = deadline - clock()
                if delay_ns > 0:
                    self._sleep(delay_ns / 1e9)
        finally:
            if self._final is not None:
                try:
                    self._final()
                except Exception:
                    _log.exception('scheduler final callback failed')

    def _record_start(self, error_ns: int) -> None:
        error_ns = abs(error_ns)
        self._timed += 1
        self._sum_error_ns += error_ns
        self._max_error_ns = max(self._max_error_ns, error_ns)
        i = 0
        for edge in self._edges_ns:
            if error_ns < edge:
                break
            i += 1
        self._histogram[i] += 1

    def stats(self) -> PeriodStats:
        """Timing statistics so far."""
        timed = self._timed
        return PeriodStats(
            period_ns=self.period_ns,
            ticks=self._ticks,
            overruns=self._overruns,
            skipped_ticks=self._skipped,
            max_error_us=self._max_error_ns / 1e3,
            mean_error_us=self._sum_error_ns / timed / 1e3 if timed else 0.0,
            histogram=tuple(self._histogram),
            max_tick_us=self._max_tick_ns / 1e3,
            errors=self._errors,
        )
