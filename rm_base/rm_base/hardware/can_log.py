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


class CanLog:
    """Frames to a python-can writer (``can.Logger``: .asc, .blf, .csv, .log, ...).

    The writer runs in its own thread; the sending and receiving threads only enqueue,
    without waking it: it writes what is queued when :meth:`wake` is called (at the end of
    each loop tick, in the loop's idle time) or every 10 ms.
    """

    def __init__(self, path: str, name: str) -> None:
        try:
            self._writer = can.Logger(path)
        except (ValueError, OSError) as err:
            raise BusError(f'bus {name}: cannot open CAN log {path!r}: {err}') from err
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
        """Log a received frame (the interface stamped it)."""
        self._queue.append(msg)

    def sent(self, msg: can.Message, channel: str) -> None:
        """Log a sent frame: a copy stamped now (wall clock, as readers expect), marked Tx."""
        logged = copy.copy(msg)
        logged.timestamp, logged.is_rx, logged.channel = time.time(), False, channel
        self._queue.append(logged)

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
