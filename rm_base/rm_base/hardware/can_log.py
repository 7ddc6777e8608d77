"""The ``log_file`` of a bus: every frame sent and received, in a python-can log format."""

from __future__ import annotations

import copy
import logging
import queue
import threading
import time

import can

from rm_base.hardware.errors import BusError

_log = logging.getLogger('rm_base.hardware.bus')


class CanLog:
    """Frames to a python-can writer (``can.Logger``: .asc, .blf, .csv, .log, ...).

    The writer runs in its own thread; the sending and receiving threads only enqueue.
    """

    def __init__(self, path: str, name: str) -> None:
        try:
            self._writer = can.Logger(path)
        except (ValueError, OSError) as err:
            raise BusError(f'bus {name}: cannot open CAN log {path!r}: {err}') from err
        self._queue: queue.SimpleQueue[can.Message | None] = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._run, name=f'canlog-{name}', daemon=True)
        self._thread.start()

    def received(self, msg: can.Message) -> None:
        """Log a received frame (the interface stamped it)."""
        self._queue.put(msg)

    def sent(self, msg: can.Message, channel: str) -> None:
        """Log a sent frame: a copy stamped now (wall clock, as readers expect), marked Tx."""
        logged = copy.copy(msg)
        logged.timestamp, logged.is_rx, logged.channel = time.time(), False, channel
        self._queue.put(logged)

    def _run(self) -> None:
        while (msg := self._queue.get()) is not None:
            try:
                self._writer.on_message_received(msg)
            except Exception:
                _log.exception('CAN log writer failed; frame dropped')

    def stop(self) -> None:
        """Write what is queued, then close the file."""
        self._queue.put(None)
        self._thread.join(timeout=5.0)
        self._writer.stop()
