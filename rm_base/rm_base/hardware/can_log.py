"""The ``log_file`` of a bus: every frame sent and received, in a python-can log format."""

from __future__ import annotations

import collections
import copy
import logging
import threading
import time

import can

from rm_base.hardware.errors import BusError

_log = logging.getLogger('rm_base.hardware.bus')

# The writer writes what is queued when woken (the loop's after-tick) or this often [s].
_DRAIN_PERIOD_S = 0.01
#: Frames the writer may fall behind by (about 10 s of a busy 1 Mbit/s bus); past it new
#: frames are dropped and counted, so a slow disk or a starved CPU cannot grow the process.
MAX_QUEUED = 20_000
# A drop is said at most this often [s].
_WARN_PERIOD_S = 1.0


class CanLog:
    """Frames to a python-can writer (``can.Logger``: .asc, .blf, .csv, .log, ...).

    The writer runs in its own thread; the sending and receiving threads only enqueue,
    without waking it: it writes what is queued when :meth:`wake` is called (at the end of
    each loop tick, in the loop's idle time) or every 10 ms. At most ``max_queued`` frames
    wait; beyond that a frame is dropped, counted (``dropped``, on the bus's /diagnostics)
    and said in a warning at most once a second. :meth:`stop` therefore writes at most
    ``max_queued`` frames (about a second) before it closes the file.
    """

    def __init__(self, path: str, name: str, max_queued: int = MAX_QUEUED) -> None:
        try:
            self._writer = can.Logger(path)
        except (ValueError, OSError) as err:
            raise BusError(f'bus {name}: cannot open CAN log {path!r}: {err}') from err
        self._name = name
        self._max = max_queued
        self.dropped = 0
        self._warned_at = -_WARN_PERIOD_S
        self._queue: collections.deque[can.Message] = collections.deque()
        self._wake = threading.Event()
        self._stopping = False
        self._thread = threading.Thread(target=self._run, name=f'canlog-{name}', daemon=True)
        self._thread.start()

    def wake(self) -> None:
        """Let the writer write what is queued."""
        if self._queue:
            self._wake.set()

    def received(self, msg: can.Message) -> None:
        """Log a received frame (the interface stamped it), marked Rx."""
        if len(self._queue) >= self._max:
            self._drop()
            return
        # socketcan says is_rx=False of a frame another process on this host sent (vcan,
        # a second program on can0); to this bus's log it is one it received
        msg.is_rx = True
        self._queue.append(msg)

    def sent(self, msg: can.Message, channel: str) -> None:
        """Log a sent frame: a copy stamped now (wall clock, as readers expect), marked Tx."""
        if len(self._queue) >= self._max:
            self._drop()
            return
        logged = copy.copy(msg)
        logged.timestamp, logged.is_rx, logged.channel = time.time(), False, channel
        self._queue.append(logged)

    def _drop(self) -> None:
        self.dropped += 1
        now = time.monotonic()
        if now - self._warned_at >= _WARN_PERIOD_S:
            self._warned_at = now
            _log.warning('bus %s: the CAN log writer is %d frames behind; %d frame(s) not '
                         'logged so far', self._name, len(self._queue), self.dropped)

    def _run(self) -> None:
        while not self._stopping:
            self._wake.wait(_DRAIN_PERIOD_S)
            self._wake.clear()
            self._drain()

    def _drain(self) -> None:
        queue = self._queue
        while queue:
            try:
                self._writer.on_message_received(queue.popleft())
            except Exception:
                _log.exception('CAN log writer failed; frame dropped')

    def stop(self) -> None:
        """Write what is queued, then close the file."""
        self._stopping = True
        self._wake.set()
        self._thread.join(timeout=5.0)
        self._drain()
        self._writer.stop()
