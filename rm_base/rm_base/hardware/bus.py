"""A managed python-can bus: send, dispatch of received frames, reconnects.

Why one module: one bus's whole life (open, send, dispatch, failure and reopen, load and
counters), which share its lock and state.

:class:`ManagedBus` wraps one ``can.Bus`` (any interface). Received frames are handed to
their owners — handlers registered per arbitration id — either by the control loop, which
calls :meth:`ManagedBus.poll` at the start of each tick (the default), or by a receive
thread of the bus; neither does control work. A bus error, bus-off or an adapter that
disappears is logged and counted, the bus is closed and reopened with exponential
back-off, and nothing raises into the caller:
:meth:`ManagedBus.send` returns False while the bus is down.

Optionally every frame sent and received is written to a python-can log file
(``can.Logger``: .asc, .blf, .log, .csv, .trc, .txt) by a writer thread, so file I/O never
runs on the 1 kHz path.
"""

from __future__ import annotations

import dataclasses
import enum
import logging
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, Protocol

import can

from rm_base.hardware.can_link import link_is_up
from rm_base.hardware.can_log import CanLog
from rm_base.hardware.config import BusConfig
from rm_base.hardware.errors import BusError
from rm_base.hardware.protocols.can_error import decode_error_frame

_log = logging.getLogger(__name__)

#: Handler of a received frame: ``handler(msg, now_ns) -> matched``.
FrameHandler = Callable[[can.Message, int], bool]


class CanBus(Protocol):
    """What the hardware layer uses of a bus: a ``can.BusABC``, or a proxy of one."""

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        """Send one frame (raises can.CanError)."""

    def recv(self, timeout: float | None = None) -> can.Message | None:
        """The next frame, or None after timeout [s]."""

    def shutdown(self) -> None:
        """Release the interface."""


#: Builds a bus: ``factory(interface=..., channel=..., **options)`` (``can.Bus``).
BusFactory = Callable[..., CanBus]

# Nominal frame lengths without bit stuffing: SOF..EOF plus 3 bits of interframe space.
_STD_FRAME_OVERHEAD_BITS = 47
_EXT_FRAME_OVERHEAD_BITS = 67


def frame_bits(msg: can.Message) -> int:
    """Nominal number of bits a classic CAN frame occupies on the wire (no stuffing).

    Used for the bus-load estimate; CAN FD frames are counted at the nominal rate, which
    overestimates their load.
    """
    overhead = _EXT_FRAME_OVERHEAD_BITS if msg.is_extended_id else _STD_FRAME_OVERHEAD_BITS
    return overhead + 8 * len(msg.data)


class BusState(enum.Enum):
    """Life cycle of a :class:`ManagedBus`."""

    NEW = 'new'  # constructed, never opened
    UP = 'up'  # open and working
    DOWN = 'down'  # failed; being reopened with back-off
    CLOSED = 'closed'  # shut down


@dataclasses.dataclass(frozen=True)
class BusStats:
    """Counters of one bus (monotonic since construction, except the load).

    Attributes:
        name: bus name.
        state: :class:`BusState` value.
        frames_sent: frames handed to the driver successfully.
        frames_received: frames received (data frames).
        frames_unmatched: received frames no handler claimed.
        frames_late: received frames that had waited more than 1 ms before the receive
            thread got them (stamped at their arrival; see ``frame_clock``).
        log_dropped: frames the ``log_file`` writer had no room for (it fell behind).
        send_errors: failed sends (driver error, buffer full, bus down).
        receive_errors: errors raised by the driver while receiving.
        error_frames: CAN error frames reported by the driver.
        last_error_frame: the last of them, decoded (classes, controller state,
            counters), or None.
        bus_off: error frames that said the controller went bus-off.
        handler_errors: exceptions raised by frame handlers (bugs; logged).
        reopen_count: successful (re)opens after the first open.
        open_failures: failed attempts to open.
        generation: number of successful opens (changes when the bus comes back).
        load_bps: estimated bits per second on the wire since the previous stats() call.
        load_fraction: load_bps / bitrate, or None without a bitrate.
        last_error: text of the last error, or None.
    """

    name: str
    state: str
    frames_sent: int
    frames_received: int
    frames_unmatched: int
    send_errors: int
    receive_errors: int
    error_frames: int
    handler_errors: int
    reopen_count: int
    open_failures: int
    generation: int
    load_bps: float
    load_fraction: float | None
    last_error: str | None
    frames_late: int = 0
    log_dropped: int = 0
    last_error_frame: str | None = None
    bus_off: int = 0


#: Largest believable age of a received frame [s]: a timestamp older than this (or in the
#: future) is on a clock of its own, and the frame is stamped at receipt.
MAX_FRAME_AGE_S = 1.0
_BACKDATE_NOTED_S = 0.001


class _Default:
    """Marks an argument left at its default."""


_DEFAULT = _Default()


class ManagedBus:
    """One CAN bus: dispatch by arbitration id (polled or a receive thread), reconnection.

    Handlers run on the polling or the receive thread; they must be quick (decode, store). A handler
    returns True if the frame was for it; a frame nobody claims is counted as unmatched.

    Example:
        >>> bus = ManagedBus(BusConfig('vcan', 'virtual', 'doc'))
        >>> bus.add_handler(0x201, lambda msg, now_ns: True)
        >>> with bus:
        ...     bus.start()
        ...     bus.send(can.Message(arbitration_id=0x200, data=bytes(8), is_extended_id=False))
        True
    """

    def __init__(
        self,
        config: BusConfig,
        *,
        clock_ns: Callable[[], int] = time.perf_counter_ns,
        bus_factory: BusFactory = can.Bus,
        frame_clock: Callable[[], float] | _Default | None = _DEFAULT,
    ) -> None:
        """Create the bus object; nothing is opened until :meth:`open` or :meth:`start`.

        Args:
            config: bus configuration.
            clock_ns: monotonic clock [ns] used to stamp received frames and for the load
                estimate (reconnect back-off always runs on real time).
            bus_factory: builds the python-can bus (``can.Bus``; tests pass fakes).
            frame_clock: the clock of the interface's ``msg.timestamp`` [s]. A frame is
                stamped at its arrival: the receive time minus its age on this clock
                (``frame_clock() - msg.timestamp``), if that age is within
                ``MAX_FRAME_AGE_S``; else (no timestamp, or a clock of its own such as an
                adapter's hardware timer) at the receive time. Default ``time.time``
                (socketcan's kernel stamps, rm_sim, python-can's virtual bus) with the
                default ``clock_ns``, None (receive time) with an injected one.
        """
        self.config = config
        self.name = config.name
        self._clock_ns = clock_ns
        if isinstance(frame_clock, _Default):
            frame_clock = time.time if clock_ns is time.perf_counter_ns else None
        self._frame_clock = frame_clock
        self._late = 0  # frames that waited > 1 ms for the receive thread
        self._factory = bus_factory
        self._bus: CanBus | None = None
        self._state = BusState.NEW
        self._handlers: dict[int, tuple[FrameHandler, ...]] = {}
        self._reopen_listeners: list[Callable[[int], None]] = []
        self._failure_listeners: list[Callable[[int], None]] = []
        self._stop = threading.Event()
        self._reopen_requested = False
        # not _thread: compiled (rm_base/runtime/compiled.py), that is __thread in C, a keyword
        self._worker: threading.Thread | None = None
        self._lock = threading.Lock()  # open/close and shutdown
        self._backoff_s = config.reconnect_initial_s
        self._reopen_delay_s = config.reconnect_initial_s
        self._reopen_at = 0.0  # [s] monotonic; poll() reopens a failed bus from then on
        self._polled = False
        self._up_since = 0.0  # when the bus last came up (time.monotonic) [s]
        self._consecutive_send_failures = 0
        self._log_sink = CanLog(config.log_file, config.name) if config.log_file else None
        self._sent_observer: Callable[[Sequence[can.Message]], object] | None = None
        # counters (single writer each: the sending thread or the receive thread)
        self._sent = 0
        self._received = 0
        self._unmatched = 0
        self._send_errors = 0
        self._receive_errors = 0
        self._error_frames = 0
        self._last_error_frame: str | None = None
        self._bus_off = 0
        self._handler_errors = 0
        self._reopen_count = 0
        self._open_failures = 0
        self._generation = 0
        self._bits = 0
        self._load_mark: tuple[int, int] = (clock_ns(), 0)
        self._last_error: str | None = None

    # --- configuration -----------------------------------------------------------------
    def add_handler(self, arbitration_id: int, handler: FrameHandler) -> None:
        """Register ``handler`` for frames with ``arbitration_id`` (several may share one)."""
        self._handlers[arbitration_id] = (*self._handlers.get(arbitration_id, ()), handler)

    def add_reopen_listener(self, listener: Callable[[int], None]) -> None:
        """Call ``listener(now_ns)`` whenever the bus comes back, before any frame is sent."""
        self._reopen_listeners.append(listener)

    def add_failure_listener(self, listener: Callable[[int], None]) -> None:
        """Call ``listener(now_ns)`` whenever the bus fails (after it was up)."""
        self._failure_listeners.append(listener)

    def _notify(self, listeners: list[Callable[[int], None]]) -> None:
        now = self._clock_ns()
        for listener in listeners:
            try:
                listener(now)
            except Exception:
                _log.exception('bus %s: listener failed', self.name)

    # --- life cycle ------------------------------------------------------------------------
    @property
    def state(self) -> BusState:
        """Current :class:`BusState`."""
        return self._state

    @property
    def generation(self) -> int:
        """Number of successful opens; changes each time the bus comes back."""
        return self._generation

    def open(self) -> bool:
        """Try to open the bus now.

        Returns:
            True if the bus is up. On failure the error is logged and counted, and the
            receive thread (if started) keeps retrying with back-off.

        Raises:
            BusError: the bus was shut down.
        """
        with self._lock:
            if self._state is BusState.CLOSED:
                raise BusError(f'bus {self.name} is shut down')
            if self._bus is not None:
                return True
            return self._open_locked()

    def _open_locked(self) -> bool:
        cfg = self.config
        kwargs: dict[str, Any] = dict(cfg.options)
        if cfg.bitrate is not None:
            kwargs.setdefault('bitrate', cfg.bitrate)
        if cfg.fd:
            kwargs.setdefault('fd', True)
            if cfg.data_bitrate is not None:
                kwargs.setdefault('data_bitrate', cfg.data_bitrate)
        if cfg.interface == 'socketcan' and link_is_up(str(cfg.channel)) is False:
            # the kernel binds a socket to a link that is down; nothing would pass until up
            self._open_failures += 1
            self._note_error(f'link {cfg.channel} is down (ip link set {cfg.channel} up)')
            self._state = BusState.DOWN
            self._schedule_reopen()
            return False
        try:
            bus = self._factory(
                interface=cfg.interface, channel=cfg.channel, ignore_config=True, **kwargs
            )
        except (can.CanError, OSError, ValueError, ImportError) as err:
            self._open_failures += 1
            self._note_error(f'open failed: {err!r}')
            self._state = BusState.DOWN
            self._schedule_reopen()
            return False
        first = self._generation == 0
        if not first:
            # before the bus is published, so no frame goes out before the owners know
            self._notify(self._reopen_listeners)
        self._consecutive_send_failures = 0
        self._reopen_requested = False
        self._up_since = time.monotonic()
        self._bus = bus
        self._generation += 1
        self._state = BusState.UP
        if first:
            _log.info('bus %s up (%s %s)', self.name, cfg.interface, cfg.channel)
        else:
            self._reopen_count += 1
            _log.warning('bus %s is back (reopen #%d)', self.name, self._reopen_count)
        return True

    def _schedule_reopen(self) -> None:
        self._reopen_delay_s = self._backoff_s
        self._reopen_at = time.monotonic() + self._backoff_s
        _log.warning('bus %s down; reopening in %.3f s', self.name, self._backoff_s)
        self._backoff_s = min(self._backoff_s * 2.0, self.config.reconnect_max_s)

    def _close_locked(self) -> None:
        bus, self._bus = self._bus, None
        if bus is not None:
            try:
                bus.shutdown()
            except Exception as err:
                _log.debug('bus %s: shutdown of the failed bus raised %r', self.name, err)

    def _fail(self, reason: str) -> None:
        """Close the bus after an error and schedule a reopen (receive thread)."""
        with self._lock:
            if self._state is BusState.CLOSED:
                return
            self._note_error(reason)
            self._close_locked()
            self._state = BusState.DOWN
            self._notify(self._failure_listeners)
            # The back-off starts over only for a bus that had stayed up for the longest
            # wait: a bus that fails as soon as it is open (a persistent bus-off) must not
            # be reopened every reconnect_initial_s forever.
            if time.monotonic() - self._up_since >= self.config.reconnect_max_s:
                self._backoff_s = self.config.reconnect_initial_s
            self._schedule_reopen()

    def start(self, *, receive_thread: bool = True) -> None:
        """Open the bus (if possible) and start the receive thread. Idempotent.

        Args:
            receive_thread: False: no thread; the control loop calls :meth:`poll` each
                tick instead (feedback taken in the loop, in lockstep too).

        Raises:
            BusError: the bus was shut down.
        """
        self.open()
        if not receive_thread:
            self._polled = True
            return
        if self._worker is None:
            self._worker = threading.Thread(
                target=self._run, name=f'canrx-{self.name}', daemon=True
            )
            self._worker.start()

    def shutdown(self) -> None:
        """Stop the receive thread, close the bus and the log. Idempotent."""
        with self._lock:
            if self._state is BusState.CLOSED:
                return
            self._state = BusState.CLOSED
        self._stop.set()
        if self._worker is not None and self._worker is not threading.current_thread():
            self._worker.join(timeout=5.0)
            if self._worker.is_alive():
                _log.error('bus %s: receive thread did not stop within 5 s', self.name)
        with self._lock:
            self._close_locked()
        if self._log_sink is not None:
            self._log_sink.stop()
        _log.info('bus %s shut down', self.name)

    def after_tick(self) -> None:
        """Let the bus's log writer write what is queued (in the loop's idle time)."""
        if self._log_sink is not None:
            self._log_sink.wake()

    def __enter__(self) -> ManagedBus:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()

    # --- sending -----------------------------------------------------------------------------
    def send(self, msg: can.Message) -> bool:
        """Send one frame; never raises for bus trouble.

        Returns:
            True if the driver accepted the frame; False if the bus is down or the send
            failed (counted; after ``send_failures_to_reopen`` consecutive failures the
            bus is reopened).
        """
        bus = self._bus
        if bus is None:
            self._send_errors += 1
            return False
        return self._sent_by(bus.send, msg, (msg,))

    def send_many(self, msgs: list[can.Message]) -> int:
        """Send a tick's frames in order; never raises.

        One driver call where the interface has ``send_many`` (rm_sim_socket: one
        datagram), else one frame at a time.

        Returns:
            How many the driver accepted.
        """
        many = getattr(self._bus, 'send_many', None)
        if many is None:
            return sum(self.send(msg) for msg in msgs)
        return len(msgs) if self._sent_by(many, msgs, msgs) else 0

    def _sent_by(self, driver_send: Any, what: Any, msgs: Sequence[can.Message]) -> bool:
        """Hand what to driver_send and count msgs as sent or failed; never raises."""
        try:
            driver_send(what, timeout=self.config.send_timeout_s)
        except (can.CanError, OSError, ValueError) as err:
            self._send_errors += len(msgs)
            self._consecutive_send_failures += 1
            if self._consecutive_send_failures == 1:
                self._note_error(f'send failed: {err!r}')
            if self._consecutive_send_failures >= self.config.send_failures_to_reopen:
                self._reopen_requested = True
            return False
        self._consecutive_send_failures = 0
        self._sent += len(msgs)
        self._bits += sum(map(frame_bits, msgs))
        if self._log_sink is not None:
            # under the interface's name, as candump writes it, so can-utils replay the log
            channel = str(self.config.channel)
            for msg in msgs:
                self._log_sink.sent(msg, channel)
        observer = self._sent_observer
        if observer is not None:
            observer(msgs)
        return True

    def observe_sent(self, observer: Callable[[Sequence[can.Message]], object] | None) -> None:
        """Call observer(frames) with the frames of each send the driver accepted; None stops.

        For measurements (the bench times commands to their first frame); it runs in the
        sending thread, the loop's, so it must be quick.
        """
        self._sent_observer = observer

    # --- receiving ---------------------------------------------------------------------------
    def poll(self) -> int:
        """Dispatch every frame received so far, without waiting (the loop's feedback stage).

        Also does what the receive thread does between frames: a failed bus is closed and
        reopened with back-off.

        Returns:
            Number of frames dispatched.
        """
        bus = self._bus
        if bus is not None and self._reopen_requested:
            self._fail('too many consecutive send failures')
            return 0
        if bus is None:
            if time.monotonic() >= self._reopen_at:
                with self._lock:
                    if self._state is not BusState.CLOSED and self._bus is None:
                        self._open_locked()
            return 0
        count = 0
        while True:
            try:
                msg = bus.recv(0.0)
            except (can.CanError, OSError, ValueError) as err:
                self._receive_errors += 1
                self._fail(f'receive failed: {err!r}')
                return count
            if msg is None:
                return count
            self.dispatch(msg, self._arrival_ns(msg))
            count += 1

    def _run(self) -> None:
        stop = self._stop
        timeout = self.config.receive_timeout_s
        while not stop.is_set():
            bus = self._bus
            if bus is not None and self._reopen_requested:
                self._fail('too many consecutive send failures')
                continue
            if bus is None:
                if stop.wait(self._reopen_delay_s):
                    break
                with self._lock:
                    if self._state is not BusState.CLOSED and self._bus is None:
                        self._open_locked()
                continue
            try:
                msg = bus.recv(timeout)
            except (can.CanError, OSError, ValueError) as err:
                if stop.is_set():
                    break
                self._receive_errors += 1
                self._fail(f'receive failed: {err!r}')
                continue
            if msg is not None:
                self.dispatch(msg, self._arrival_ns(msg))

    def _arrival_ns(self, msg: can.Message) -> int:
        """When msg reached the interface, on ``clock_ns`` (see ``frame_clock``).

        A receive thread that lost the CPU (a busy process) finds frames queued; stamped
        at receipt, feedback from before the stall would count as fresh.
        """
        now_ns = self._clock_ns()
        if self._frame_clock is None or not msg.timestamp:
            return now_ns
        age_s = self._frame_clock() - msg.timestamp
        if not 0.0 < age_s <= MAX_FRAME_AGE_S:
            return now_ns
        if age_s > _BACKDATE_NOTED_S:
            self._late += 1
        return now_ns - int(age_s * 1e9)

    def dispatch(self, msg: can.Message, now_ns: int) -> int:
        """Hand a received frame to its handlers (the receive thread calls this).

        Returns:
            Number of handlers that claimed the frame.
        """
        if msg.is_error_frame:
            self._error_frames += 1
            report = decode_error_frame(msg.arbitration_id, bytes(msg.data))
            self._last_error_frame = report.describe()
            if report.bus_off:
                self._bus_off += 1
            return 0
        self._received += 1
        self._bits += frame_bits(msg)
        if self._log_sink is not None:
            self._log_sink.received(msg)
        claimed = 0
        for handler in self._handlers.get(msg.arbitration_id, ()):
            try:
                if handler(msg, now_ns):
                    claimed += 1
            except Exception:
                self._handler_errors += 1
                _log.exception('bus %s: handler for 0x%X failed', self.name, msg.arbitration_id)
        if not claimed:
            self._unmatched += 1
        return claimed

    # --- diagnostics ---------------------------------------------------------------------------
    def _note_error(self, text: str) -> None:
        self._last_error = text
        _log.warning('bus %s: %s', self.name, text)

    @property
    def frames_sent(self) -> int:
        """Frames the driver accepted so far (``stats()`` without resetting the load)."""
        return self._sent

    def stats(self) -> BusStats:
        """Counters and the bus load since the previous call."""
        now = self._clock_ns()
        bits = self._bits
        then, bits_then = self._load_mark
        self._load_mark = (now, bits)
        elapsed_s = (now - then) / 1e9
        load = (bits - bits_then) / elapsed_s if elapsed_s > 0 else 0.0
        bitrate = self.config.bitrate
        return BusStats(
            name=self.name,
            state=self._state.value,
            frames_sent=self._sent,
            frames_received=self._received,
            frames_unmatched=self._unmatched,
            send_errors=self._send_errors,
            receive_errors=self._receive_errors,
            error_frames=self._error_frames,
            handler_errors=self._handler_errors,
            reopen_count=self._reopen_count,
            open_failures=self._open_failures,
            generation=self._generation,
            load_bps=load,
            load_fraction=load / bitrate if bitrate else None,
            last_error=self._last_error,
            frames_late=self._late,
            log_dropped=self._log_sink.dropped if self._log_sink is not None else 0,
            last_error_frame=self._last_error_frame,
            bus_off=self._bus_off,
        )
