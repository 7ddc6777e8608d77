"""The robot's one control loop: components in their derived order, at a fixed rate.

One dedicated thread sleeps to absolute deadlines on ``time.perf_counter_ns`` (1 kHz by
default) and runs :meth:`Scheduler.tick`; tests call ``tick(now_ns)`` themselves, with no
thread, for deterministic (lockstep) steps. A tick runs every *component* once:

- the loop's own three: ``actuators`` (every actuator's ``update(now_ns, dt)``: control
  laws, safety), ``pack`` (``pack_command()`` of every packer) and ``send`` (each packed
  frame through the send function paired with its packer);
- the stages added (:meth:`Scheduler.add_stage`): the received feedback, what the serial
  devices sent, the commands, each plugin that is due, a power limit per group...

Each component declares what it reads and writes (:mod:`rm_base.loop.data`) and the order
follows from that (:mod:`rm_base.loop.order`): the feedback and the plugins before the
actuators (they write the states and targets the actuators read), a power limit between
the actuators and ``pack`` (it modifies the efforts). Adding a component is declaring its
data; a cycle, or an output nothing reads, is a :class:`LoopConfigError` naming the
components. Several additions check together inside :meth:`Scheduler.compose`.

After the components, the *after-tick callbacks* (:meth:`Scheduler.add_after_tick`) only
wake the threads of the ROS edge (the publishers, which read what the tick left), so those
run in the loop's idle time instead of taking the interpreter from it mid-tick; then, in
the loop's thread, the interpreter's garbage collection when one is due
(:mod:`rm_base.loop.garbage`): never in the middle of a tick.

A tick that ends after the next deadline is an overrun (a missed deadline): the next tick
then starts at once, late, if its period has not passed yet (as a firmware loop on
``vTaskDelayUntil`` does); periods that passed whole are skipped and counted, never caught
up in a burst. The loop measures itself: start lateness and the duration of every
component as p50 / p99 / max (:mod:`rm_base.loop.timing`), and logs the window every
``report_period_s`` with the three most expensive components. An exception escaping a
tick goes to ``on_error(exc)``, which decides whether to go on (as python-can's
``ThreadBasedCyclicSendTask``); without a hook the loop stops.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Protocol

import can

from rm_base.loop import garbage
from rm_base.loop.data import FRAMES, JOINT_EFFORTS, JOINT_GAINS, JOINT_STATES, JOINT_TARGETS
from rm_base.loop.errors import LoopConfigError
from rm_base.loop.order import Declared, derive_order, unread_outputs
from rm_base.loop.timing import (
    HISTOGRAM_EDGES_US,
    DurationHistogram,
    DurationSummary,
    PeriodStats,
)
from rm_base.runtime.realtime import loop_thread, set_fifo_priority

_log = logging.getLogger(__name__)


class Updatable(Protocol):
    """Anything updated once per tick (an actuator)."""

    def update(self, now_ns: int, dt: float) -> None:
        """Compute this tick's output."""


class Packer(Protocol):
    """Anything that packs a frame per tick (an actuator or a command group)."""

    def pack_command(self) -> can.Message | None:
        """Return this tick's frame, or None."""


class Stage(Declared, Protocol):
    """A component of the loop besides the actuators (feedback, a plugin, a power limit).

    Its ``name`` is its name in the timing statistics (``plugin chassis``); ``reads`` and
    ``writes`` name its data (:mod:`rm_base.loop.data`): a datum it reads and writes, it
    modifies.
    """

    def __call__(self, now_ns: int, dt: float) -> bool | None:
        """Do this tick's work; return False if there was none (then it is not timed)."""


#: Names of the loop's own components in :meth:`Scheduler.component_stats`.
ACTUATORS, PACK, SEND = 'actuators', 'pack', 'send'
#: The garbage collections the loop thread ran after its ticks (not part of a tick).
GC = 'gc'
_OWN = (ACTUATORS, PACK, SEND)


class _Update:
    """The loop's ``actuators`` component: every actuator's update."""

    name = ACTUATORS
    reads = (JOINT_TARGETS, JOINT_STATES, JOINT_GAINS)
    writes = (JOINT_EFFORTS,)

    def __init__(self, actuators: tuple[Updatable, ...]) -> None:
        self._actuators = actuators

    def __call__(self, now_ns: int, dt: float) -> bool:
        for actuator in self._actuators:
            actuator.update(now_ns, dt)
        return True


class _Pack:
    """The loop's ``pack`` component: this tick's frame of every packer, with its send."""

    name = PACK
    reads = (JOINT_EFFORTS,)
    writes = (FRAMES,)

    def __init__(
        self,
        packers: tuple[tuple[Packer, Callable[[can.Message], object]], ...],
        frames: list[tuple[Callable[[can.Message], object], can.Message]],
    ) -> None:
        self._packers = packers
        self.frames = frames

    def __call__(self, now_ns: int, dt: float) -> bool:
        frames = self.frames
        frames.clear()
        for packer, send in self._packers:
            msg = packer.pack_command()
            if msg is not None:
                frames.append((send, msg))
        return True


class _Send:
    """The loop's ``send`` component: the packed frames, then the flush."""

    name = SEND
    reads = (FRAMES,)
    writes: tuple[str, ...] = ()

    def __init__(
        self,
        frames: list[tuple[Callable[[can.Message], object], can.Message]],
        flush: Callable[[], object] | None,
    ) -> None:
        self.frames = frames
        self._flush = flush

    def __call__(self, now_ns: int, dt: float) -> bool:
        for send, msg in self.frames:
            send(msg)
        if self._flush is not None:
            self._flush()
        return True


class _Edge:
    """An after-tick callback as the order sees it: a reader of what the tick left."""

    writes: tuple[str, ...] = ()

    def __init__(self, callback: Callable[[], object], reads: tuple[str, ...]) -> None:
        self.name = f'after tick {getattr(callback, "__qualname__", callback)!s}'
        self.callback = callback
        self.reads = reads


def _check_read(components: tuple[Stage, ...], edges: tuple[_Edge, ...]) -> None:
    """Raise LoopConfigError naming each output of components that nothing reads."""
    unread = unread_outputs(components + edges)
    if unread:
        text = '; '.join(f'{name!r} writes {datum!r}' for name, datum in unread)
        raise LoopConfigError(f'the loop has outputs that nothing reads: {text}')


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
        report_period_s: float = 5.0,
        thread_name: str = 'can-scheduler',
        flush: Callable[[], object] | None = None,
        priority: int = 0,
        set_priority: Callable[[int], None] | None = None,
        collect_garbage: bool = True,
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
            clock_ns: monotonic clock [ns] of the ticks (a simulated one in lockstep).
            sleep: sleep function [s] (tests may replace it).
            report_period_s: the thread logs its timing window this often [s].
            thread_name: name of the loop thread.
            flush: called after the frames of a tick were handed to their ``send``
                functions (which may only collect them), within the ``send`` component.
            priority: real-time priority of the loop thread (SCHED_FIFO, 1-99), as
                ros2_control's controller manager asks for its thread; 0 keeps the
                normal scheduling. Without the right to it the loop runs on, with one
                warning.
            set_priority: applies the priority to the calling thread (tests replace it).
            collect_garbage: while the thread runs, the process's garbage collection is
                the loop's, after its ticks (:mod:`rm_base.loop.garbage`); False
                leaves it to the interpreter.

        Raises:
            LoopConfigError: rate_hz not positive, priority outside 0-99.
        """
        if not rate_hz > 0:
            raise LoopConfigError(f'scheduler rate must be > 0 Hz, got {rate_hz!r}')
        if not 0 <= priority <= 99:
            raise LoopConfigError(f'scheduler priority must be 0-99, got {priority!r}')
        self.priority = priority
        self._set_priority = set_priority or set_fifo_priority
        self._frames: list[tuple[Callable[[can.Message], object], can.Message]] = []
        # every component in the order added (the order's tie-break), the loop's own first
        self._components: tuple[Stage, ...] = (
            _Update(tuple(actuators)),
            _Pack(tuple(packers), self._frames),
            _Send(self._frames, flush),
        )
        self._order: tuple[Stage, ...] = self._components
        self._edges: tuple[_Edge, ...] = ()
        self._after_tick: tuple[Callable[[], object], ...] = ()
        self._composing = 0
        self._report_period_ns = round(report_period_s * 1e9)
        self._thread_name = thread_name
        self._collect_garbage = collect_garbage
        self._lateness = DurationHistogram()
        self._durations: dict[str, DurationHistogram] = {}
        for name in (ACTUATORS, PACK, SEND, GC):
            self._durations[name] = DurationHistogram()
        self.period_ns = round(1e9 / rate_hz)
        self._period_s = self.period_ns / 1e9
        self.on_error = on_error
        self._clock_ns = clock_ns
        self._sleep = sleep
        self._last_tick_ns: int | None = None
        self._tick_deadline_ns: int | None = None
        self._observer: Callable[[int, int], object] | None = None
        self._stop = threading.Event()
        # not _thread: compiled (rm_base/runtime/compiled.py), that is __thread in C, a keyword
        self._worker: threading.Thread | None = None
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

    # --- composition ---
    def add_stage(self, stage: Stage) -> None:
        """Add a component; it runs where its declared reads and writes put it.

        A stage added while the loop runs joins at its next tick (the order is swapped
        whole, never changed in place). Inside :meth:`compose` the checks wait for its end.

        Raises:
            LoopConfigError: a component of that name exists already; the stage closes a
                cycle; outside ``compose``, an output that no component reads.
        """
        names = {s.name for s in self._components} | {GC}
        if stage.name in names:
            raise LoopConfigError(f'the loop has a component named {stage.name!r} already')
        self._durations.setdefault(stage.name, DurationHistogram())
        self._rearrange((*self._components, stage), self._edges)

    def remove_stage(self, name: str) -> bool:
        """Remove the stage of that name from the loop (from its next tick on).

        The loop's own components stay. No check: a removal leaves no cycle, and an output
        its reader's removal leaves unread is the remover's (a plugin's port goes with it).

        Returns:
            Whether there was one. A tick in progress in the loop thread may still be
            running it: the caller must wait for it by its own means (a lock).
        """
        if name in (ACTUATORS, PACK, SEND):
            return False
        kept = tuple(s for s in self._components if s.name != name)
        found = len(kept) < len(self._components)
        # Its timing stays: a tick in progress may still record into it.
        self._components = kept
        self._order = tuple(s for s in self._order if s.name != name)
        return found

    def add_after_tick(
        self, callback: Callable[[], object], reads: tuple[str, ...] = ()
    ) -> None:
        """Call callback() at the end of every tick, after the frames went out.

        For waking threads (``threading.Event.set``) of the ROS edge, which then read the
        data named in reads (they count as read for the checks): it must not block or take
        long.
        """
        self._after_tick += (callback,)
        if reads:
            self._rearrange(self._components, (*self._edges, _Edge(callback, reads)))

    def remove_after_tick(self, callback: Callable[[], object]) -> None:
        """Stop calling callback after the ticks (no error if it was not added)."""
        self._after_tick = tuple(c for c in self._after_tick if c != callback)
        self._edges = tuple(e for e in self._edges if e.callback != callback)

    @contextlib.contextmanager
    def compose(self) -> Iterator[None]:
        """Check the components added inside together, at the end (a host's plugins).

        A plugin's device stage writes what its plugin, added later, reads: checked one
        by one, the first would be an unread output.

        Raises:
            LoopConfigError: at the end, an output that no component reads.
        """
        self._composing += 1
        try:
            yield
        finally:
            self._composing -= 1
        if not self._composing:
            self.check()

    def check(self) -> None:
        """Raise if a component's output is read by no component (nor the ROS edge).

        Raises:
            LoopConfigError: naming the component and the datum.
        """
        _check_read(self._components, self._edges)

    def _rearrange(self, components: tuple[Stage, ...], edges: tuple[_Edge, ...]) -> None:
        """Derive the order of components, check it, and make it the loop's."""
        order = tuple(components[i] for i in derive_order(components, _OWN))
        if not self._composing:
            _check_read(components, edges)
        self._components, self._edges, self._order = components, edges, order

    def order(self) -> tuple[str, ...]:
        """The components' names in the order a tick runs them."""
        return tuple(s.name for s in self._order)

    def observe_ticks(self, observer: Callable[[int, int], object] | None) -> None:
        """Call observer(start_error_ns, tick_ns) after each tick of the thread; None stops.

        For measurements that need every tick (the bench's percentiles), where the loop
        itself keeps histograms: ``start_error_ns`` is the tick's start minus its deadline,
        ``tick_ns`` the time from that start to the end of ``tick`` (the loop's own
        bookkeeping at the start included, its window log every ``report_period_s`` too).
        """
        self._observer = observer

    # --- one cycle ---
    def tick(self, now_ns: int) -> int:
        """Run one cycle: every component in the derived order, then the after-tick calls.

        Args:
            now_ns: the tick time [ns] on the actuators' clock.

        Returns:
            Number of frames handed to ``send``.
        """
        last = self._last_tick_ns
        dt = (now_ns - last) / 1e9 if last is not None and now_ns > last else self._period_s
        self._last_tick_ns = now_ns
        durations, timer = self._durations, time.perf_counter_ns
        # durations are real CPU-side time, even in lockstep
        t = timer()
        for stage in self._order:
            worked = stage(now_ns, dt) is not False
            t1 = timer()
            if worked:
                durations[stage.name].record(t1 - t)
            t = t1
        self._ticks += 1
        for callback in self._after_tick:
            callback()
        return len(self._frames)

    # --- the thread ---
    @property
    def running(self) -> bool:
        """Whether the scheduler thread is alive."""
        return self._worker is not None and self._worker.is_alive()

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
        self._worker = threading.Thread(target=self._run, name=self._thread_name, daemon=True)
        self._worker.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop the thread and wait for it (including ``final``). Idempotent."""
        self._stop.set()
        thread = self._worker
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout_s)
            if thread.is_alive():
                _log.error('scheduler thread did not stop within %.1f s', timeout_s)

    def _run(self) -> None:
        if self.priority:
            try:
                self._set_priority(self.priority)
            except OSError as err:  # no CAP_SYS_NICE / RLIMIT_RTPRIO: still a loop
                _log.warning(
                    'the loop runs without real-time priority (SCHED_FIFO %d: %s); '
                    'see docs/PERFORMANCE.md', self.priority, err,
                )
        # before the first deadline: taking over collects once, which takes a while
        holder = garbage.take_over(1e9 / self.period_ns) if self._collect_garbage else None
        try:
            with loop_thread():  # its log lines are written by another thread
                self._loop(holder)
        finally:
            if holder is not None:
                garbage.give_back(holder)
            if self._final is not None:
                try:
                    self._final()
                except Exception:
                    _log.exception('scheduler final callback failed')

    def _loop(self, holder: garbage.Holder | None) -> None:
        """Tick until stopped or a tick's error ends the loop (``_run``'s body)."""
        clock = self._clock_ns
        period = self.period_ns
        gc_time = self._durations[GC]
        deadline = clock()
        next_report = deadline + self._report_period_ns
        while not self._stop.is_set():
            start = clock()
            self._record_start(start - deadline)
            if start >= next_report:
                next_report = start + self._report_period_ns
                self._log_window()
            self._tick_deadline_ns = deadline + period
            try:
                self.tick(start)
            except Exception as exc:
                self._errors += 1
                _log.exception('scheduler tick failed')
                if self.on_error is None or not self.on_error(exc):
                    _log.error('scheduler stopped after an error')
                    break
            self._tick_deadline_ns = None
            observer = self._observer
            if observer is not None:
                observer(start - deadline, clock() - start)
            if holder is not None:
                t0 = time.perf_counter_ns()
                if garbage.collect_if_due(holder) is not None:
                    gc_time.record(time.perf_counter_ns() - t0)
            end = clock()
            self._max_tick_ns = max(self._max_tick_ns, end - start)
            deadline += period
            if end > deadline:
                self._overruns += 1
                # Late by less than a period: the next tick runs at once, late, in its
                # own period. Periods that passed whole are skipped, never burst.
                missed = (end - deadline) // period
                self._skipped += missed
                deadline += missed * period
            delay_ns = deadline - clock()
            if delay_ns > 0:
                self._sleep(delay_ns / 1e9)

    def time_left_ns(self) -> int | None:
        """Time until the running tick's deadline (the next period's start) [ns].

        None outside a tick of the loop thread: a tick run by ``tick()`` directly (a
        stepped loop) has no deadline.
        """
        deadline = self._tick_deadline_ns
        return None if deadline is None else deadline - self._clock_ns()

    def _log_window(self) -> None:
        lateness = self._lateness.take_window()
        # a copy: the host may add a stage meanwhile (list() of a dict is one GIL step)
        windows = [(name, h.take_window()) for name, h in list(self._durations.items())]
        top = sorted(windows, key=lambda item: item[1].p99_us, reverse=True)[:3]
        _log.info(
            'loop: %d ticks, %d skipped in all; lateness p50 %.0f / p99 %.0f / max %.0f us; '
            'most expensive (p99): %s',
            lateness.count, self._skipped, lateness.p50_us, lateness.p99_us, lateness.max_us,
            ', '.join(f'{name} {s.p99_us:.0f} us' for name, s in top),
        )

    def component_stats(self) -> tuple[tuple[str, DurationSummary], ...]:
        """Duration of each component since start, in loop order (then ``gc``)."""
        order = [s.name for s in self._order] + [GC]
        return tuple((name, self._durations[name].total()) for name in order)

    def _record_start(self, error_ns: int) -> None:
        self._lateness.record(error_ns)
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
            lateness=self._lateness.total(),
            components=self.component_stats(),
        )
