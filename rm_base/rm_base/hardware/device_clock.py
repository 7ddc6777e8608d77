"""Host time of a device's samples, from the device's own clock (pure; no I/O).

A serial sensor (the HiPNUC IMU) stamps its frames with a millisecond counter but the
port gives no receive time per byte: a reader that lost the CPU for 100 ms finds 40 frames
waiting, and stamped at the read they would all look fresh. ``DeviceClock`` maps device
time to host time by the offset ``receive - device`` of the frame that came through
fastest in a sliding window: the smallest offset is the one with the least queueing, and
the window follows the drift between the two clocks (tens of ppm). A device restart or a
counter jump (the offset moving by more than ``max_jump_s``) starts the estimate over. A
counter that does not move (a device that leaves the field zero) is no clock: such a
sample is stamped at its receipt.

Example:
    >>> clock = DeviceClock(wrap_ms=2**32)
    >>> clock.stamp_ns(device_ms=1000, receive_ns=5_000_000_000)
    5000000000
    >>> clock.stamp_ns(device_ms=1010, receive_ns=5_010_000_000)  # no queueing
    5010000000
    >>> clock.stamp_ns(device_ms=1020, receive_ns=5_150_000_000)  # read 130 ms late
    5020000000
"""

from __future__ import annotations

import collections

_NS_PER_MS = 1_000_000


class DeviceClock:
    """Host time [ns] of device timestamps [ms] (see the module docstring).

    Args:
        wrap_ms: the device counter wraps to 0 at this value (2**32 for a uint32).
        window_s: how far back the fastest frame is looked for [s].
        max_jump_s: an offset change larger than this restarts the estimate [s].
    """

    def __init__(self, wrap_ms: int = 2**32, window_s: float = 2.0,
                 max_jump_s: float = 1.0) -> None:
        if wrap_ms <= 0 or window_s <= 0.0 or max_jump_s <= 0.0:
            raise ValueError('wrap_ms, window_s and max_jump_s must be > 0')
        self._wrap = wrap_ms
        self._window_ns = round(window_s * 1e9)
        self._max_jump_ns = round(max_jump_s * 1e9)
        self._last_raw: int | None = None
        self._device_ns = 0  # unwrapped device time [ns]
        # (receive time, offset) pairs whose offsets increase: the front is the minimum
        self._candidates: collections.deque[tuple[int, int]] = collections.deque()
        self.restarts = 0

    def stamp_ns(self, device_ms: int, receive_ns: int) -> int:
        """Host time [ns] at which the device took the sample; never after receive_ns."""
        raw = device_ms % self._wrap
        if raw == self._last_raw:
            return receive_ns
        if self._last_raw is None:
            self._device_ns = raw * _NS_PER_MS
        else:
            step = (raw - self._last_raw) % self._wrap
            if step > self._wrap // 2:  # backwards: a restart or a reordered counter
                step -= self._wrap
            self._device_ns += step * _NS_PER_MS
        self._last_raw = raw
        offset = receive_ns - self._device_ns
        candidates = self._candidates
        if candidates and abs(offset - candidates[0][1]) > self._max_jump_ns:
            candidates.clear()
            self.restarts += 1
        while candidates and candidates[-1][1] >= offset:
            candidates.pop()
        candidates.append((receive_ns, offset))
        while receive_ns - candidates[0][0] > self._window_ns:
            candidates.popleft()
        return min(receive_ns, self._device_ns + candidates[0][1])
