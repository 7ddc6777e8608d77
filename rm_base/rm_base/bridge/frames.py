"""A tap on every CAN frame the hardware layer sends and receives, for ``~/frames``.

:class:`FrameTap` wraps the python-can bus factory CanHardware uses. Each bus it builds
is a thin proxy that forwards ``send``/``recv``/``shutdown`` and appends every frame that
went through (the message object itself: the layer builds a new one per frame) to a
bounded queue; the node's publisher thread drains it. The 1 kHz path only pays a
``deque.append``; when nobody drains fast enough the oldest frames are dropped and
counted, never blocking a send.
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Mapping
from typing import Any, NamedTuple

import can

from rm_base.hardware.bus import BusFactory, CanBus

#: Default queue length [frames]: about one second of two busy buses at 1 kHz.
DEFAULT_MAX_FRAMES = 4096


class TappedFrame(NamedTuple):
    """One frame seen on a bus.

    Attributes:
        bus: bus name from the config.
        frame: the python-can message.
        is_rx: True if received, False if sent by the bridge.
        stamp_ns: wall-clock time it went through [ns since the epoch].
    """

    bus: str
    frame: can.Message
    is_rx: bool
    stamp_ns: int


class _TappedBus:
    """Proxy of a python-can bus that reports every frame to the tap."""

    def __init__(self, inner: CanBus, bus: str, tap: FrameTap) -> None:
        self._inner = inner
        self._bus = bus
        self._tap = tap

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._inner.send(msg, timeout=timeout)
        self._tap.record(self._bus, msg, False)

    def recv(self, timeout: float | None = None) -> can.Message | None:
        msg = self._inner.recv(timeout)
        if msg is not None:
            self._tap.record(self._bus, msg, True)
        return msg

    def shutdown(self) -> None:
        self._inner.shutdown()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)


class FrameTap:
    """Collects the frames of every bus built through :meth:`factory`.

    Args:
        bus_names: bus name per ``(interface, channel)``, to label frames.
        inner_factory: builds the real bus (``can.Bus``).
        max_frames: queue length; older frames are dropped beyond it.
    """

    def __init__(
        self,
        bus_names: Mapping[tuple[str, str], str],
        inner_factory: BusFactory = can.Bus,
        max_frames: int = DEFAULT_MAX_FRAMES,
    ) -> None:
        self._names = dict(bus_names)
        self._inner_factory = inner_factory
        self._frames: collections.deque[TappedFrame] = collections.deque(maxlen=max_frames)
        self._lock = threading.Lock()
        self.dropped = 0

    def factory(self, *, interface: str, channel: Any, **kwargs: Any) -> _TappedBus:
        """A bus factory for CanHardware: the real bus, tapped."""
        inner = self._inner_factory(interface=interface, channel=channel, **kwargs)
        name = self._names.get((interface, str(channel)), str(channel))
        return _TappedBus(inner, name, self)

    def record(self, bus: str, msg: can.Message, is_rx: bool) -> None:
        """Queue one frame (any thread)."""
        frames = self._frames
        if len(frames) == frames.maxlen:
            with self._lock:
                self.dropped += 1
        frames.append(TappedFrame(bus, msg, is_rx, time.time_ns()))

    def drain(self) -> list[TappedFrame]:
        """Take every queued frame, oldest first."""
        frames = self._frames
        out = []
        while True:
            try:
                out.append(frames.popleft())
            except IndexError:
                return out
