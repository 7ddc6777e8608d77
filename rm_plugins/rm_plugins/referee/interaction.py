"""0x0301 frames out on the referee link, within the referee's limits.

docs/PROTOCOLS.md §6.4: a robot's 0x0301 traffic may be at most 3,720 bytes a second and
at most 30 frames a second (10 in older tables; the default here). After a frame of
``size`` bytes the next waits ``1 / min(max_hz, floor(bytes_per_s / size))`` s: at that
spacing no window of a second holds more than either limit (RMCS paces by
``size / bytes_per_s`` alone, which lets a window hold one frame more than the bytes
allow).
Frames offered faster than that wait in a short queue; one that finds it full pushes out
the oldest, counted.
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass

from rm_base.errors import InputRejectedError
from rm_base.hardware.protocols.referee import client_id, encode_frame, interaction
from rm_base.hardware.protocols.referee.client_ui import (
    INTERACTION_CMD_ID,
    MAX_BYTES_PER_S,
    MAX_CONTENT_LENGTH,
)

_NS_PER_S = 1_000_000_000


@dataclass
class InteractionStats:
    """What the link did (monotonic counters)."""

    offered: int = 0
    sent: int = 0
    bytes_sent: int = 0
    dropped: int = 0  # pushed out of a full queue
    refused: int = 0  # content too long or an id out of range


class InteractionLink:
    """The queue and pacing of the robot's 0x0301 frames (see the module docstring).

    Args:
        bytes_per_s: most bytes a second, whole frames counted.
        max_hz: most frames a second.
        queue: frames kept waiting at most.
    """

    def __init__(self, bytes_per_s: float = MAX_BYTES_PER_S, max_hz: float = 10.0,
                 queue: int = 8) -> None:
        if not (bytes_per_s > 0 and max_hz > 0 and queue > 0):
            raise ValueError('bytes_per_s, max_hz and queue must be > 0')
        self.bytes_per_s = bytes_per_s
        self.max_hz = max_hz
        self.stats = InteractionStats()
        self._queue: collections.deque[tuple[int, int, bytes]] = collections.deque()
        self._capacity = queue
        self._next_ns: int | None = None
        self._seq = 0

    def offer(self, content_id: int, receiver_id: int, content: bytes) -> None:
        """Queue one frame's content (receiver 0: the robot's own client).

        Raises:
            InputRejectedError: content beyond 112 bytes or an id beyond 16 bits (counted).
        """
        self.stats.offered += 1
        if len(content) > MAX_CONTENT_LENGTH or not (
                0 <= content_id <= 0xFFFF and 0 <= receiver_id <= 0xFFFF):
            self.stats.refused += 1
            raise InputRejectedError(
                f'0x0301 content 0x{content_id:04X} to {receiver_id}: {len(content)} bytes '
                f'(at most {MAX_CONTENT_LENGTH}), ids of 16 bits')
        if len(self._queue) == self._capacity:
            self._queue.popleft()
            self.stats.dropped += 1
        self._queue.append((content_id, receiver_id, bytes(content)))

    @property
    def waiting(self) -> int:
        """Frames in the queue."""
        return len(self._queue)

    def take(self, robot_id: int | None, now_ns: int) -> bytes | None:
        """The next whole frame if one is due now, else None (robot_id None: not known yet)."""
        if not self._queue or (self._next_ns is not None and now_ns < self._next_ns):
            return None
        if robot_id is None:  # they wait (the queue's limit counts what is pushed out)
            return None
        content_id, receiver, content = self._queue.popleft()
        data = interaction(content_id, robot_id, receiver or client_id(robot_id), content)
        frame = encode_frame(INTERACTION_CMD_ID, data, seq=self._seq)
        self._seq = (self._seq + 1) & 0xFF
        per_s = min(self.max_hz, max(1, math.floor(self.bytes_per_s / len(frame))))
        gap_s = 1.0 / per_s
        self._next_ns = now_ns + math.ceil(gap_s * _NS_PER_S)
        self.stats.sent += 1
        self.stats.bytes_sent += len(frame)
        return frame
