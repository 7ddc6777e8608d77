"""The operator's client as rm_sim's referee relays the robot's 0x0301 frames to it.

It keeps the figures the robot drew, by name, as the client would show them, and checks
what the referee and the client would refuse or punish (docs/PROTOCOLS.md §6.4): a frame
beyond 30 a second or 3,720 bytes a second (any window of one second, whole frames), a
wrong sender or receiver, a content id or layout it does not know, a figure modified or
deleted that it does not show. Each is counted under its reason; the figures still apply
where they can. :meth:`SimClient.reconnect` is a client started anew: no figure shown.
"""

from __future__ import annotations

import collections
from collections import Counter
from dataclasses import dataclass, replace

from rm_base.hardware.errors import ValueRangeError
from rm_base.hardware.protocols.referee import (
    DeleteOp,
    Figure,
    FigureOp,
    RawFrame,
    client_id,
    decode_drawing,
    decode_interaction,
)
from rm_base.hardware.protocols.referee.client_ui import (
    DELETE_FIGURES,
    FRAME_OVERHEAD,
    MAX_BYTES_PER_S,
    MAX_FRAMES_PER_S,
)

_NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class Shown:
    """A figure on the client's screen (op ADD), and its text if it is one."""

    figure: Figure
    text: str | None = None


class SimClient:
    """The robot's client (see the module docstring).

    Args:
        robot_id: the robot whose client it is.
    """

    def __init__(self, robot_id: int) -> None:
        self.robot_id = robot_id
        self.shown: dict[bytes, Shown] = {}
        self.errors: Counter[str] = Counter()
        self.frames = 0
        self.bytes = 0
        self.reconnects = 0
        #: The most frames and bytes seen in any window of one second.
        self.peak_frames_per_s = 0
        self.peak_bytes_per_s = 0
        self._window: collections.deque[tuple[int, int]] = collections.deque()  # (ns, bytes)
        self._window_bytes = 0

    def reconnect(self) -> None:
        """The client restarted: it shows nothing until the robot draws again."""
        self.shown.clear()
        self.reconnects += 1

    def on_frame(self, frame: RawFrame, now_ns: int) -> None:
        """Take one 0x0301 frame from the robot."""
        size = len(frame.data) + FRAME_OVERHEAD
        self.frames += 1
        self.bytes += size
        self._count_rate(size, now_ns)
        try:
            message = decode_interaction(frame.data)
        except ValueRangeError:
            self.errors['malformed'] += 1
            return
        if message.sender_id != self.robot_id:
            self.errors['wrong sender'] += 1
            return
        if message.receiver_id != client_id(self.robot_id):
            self.errors['not to its client'] += 1
            return
        if message.content_id == DELETE_FIGURES:
            self._delete(message.content)
            return
        try:
            figures, text = decode_drawing(message.content_id, message.content)
        except ValueRangeError:
            self.errors['unknown content'] += 1
            return
        for figure in figures:
            self._apply(figure, text)

    def _count_rate(self, size: int, now_ns: int) -> None:
        window = self._window
        window.append((now_ns, size))
        self._window_bytes += size
        while window[0][0] <= now_ns - _NS_PER_S:
            self._window_bytes -= window.popleft()[1]
        self.peak_frames_per_s = max(self.peak_frames_per_s, len(window))
        self.peak_bytes_per_s = max(self.peak_bytes_per_s, self._window_bytes)
        if len(window) > MAX_FRAMES_PER_S:
            self.errors[f'over {MAX_FRAMES_PER_S} frames/s'] += 1
        if self._window_bytes > MAX_BYTES_PER_S:
            self.errors[f'over {MAX_BYTES_PER_S} bytes/s'] += 1

    def _delete(self, content: bytes) -> None:
        if len(content) != 2 or content[0] not in (DeleteOp.LAYER, DeleteOp.ALL):
            self.errors['bad delete'] += 1
            return
        if content[0] == DeleteOp.ALL:
            self.shown.clear()
        else:
            self.shown = {n: s for n, s in self.shown.items() if s.figure.layer != content[1]}

    def _apply(self, figure: Figure, text: str | None) -> None:
        name = figure.name
        if figure.op is FigureOp.ADD:
            self.shown[name] = Shown(figure, text)
        elif figure.op is FigureOp.MODIFY:
            if name not in self.shown:
                self.errors['modify of a figure not shown'] += 1
                return
            self.shown[name] = Shown(replace(figure, op=FigureOp.ADD), text)
        elif self.shown.pop(name, None) is None:  # DELETE
            self.errors['delete of a figure not shown'] += 1
