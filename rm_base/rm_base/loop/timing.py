"""The loop's timing statistics: p50 / p99 / max per component, and PeriodStats.

A :class:`DurationHistogram` counts durations in geometric buckets (5 % wide, 1 µs to
10 s), so recording is one ``bisect`` and a list increment, and a percentile is read off
the counts with at most 5 % error. It keeps two sets of counts: the current *window*
(reset by :meth:`DurationHistogram.take_window`, which the loop calls every few seconds
for its report) and the *total* since start. No locks: the loop thread records; readers
in other threads copy a list, which may be one record behind, and that is fine for
statistics.
"""

from __future__ import annotations

import bisect
import dataclasses
import math

#: Bucket edges [ns]: 1 µs * 1.05^i up to 10 s; a duration falls in the first bucket
#: whose edge is above it, the last bucket holds the rest.
_RATIO = 1.05
BUCKET_EDGES_NS: tuple[int, ...] = tuple(
    round(1_000 * _RATIO**i) for i in range(int(math.log(1e7) / math.log(_RATIO)) + 2)
)


@dataclasses.dataclass(frozen=True)
class DurationSummary:
    """Percentiles of a set of durations.

    Attributes:
        count: durations recorded.
        p50_us: median [µs] (upper edge of its bucket: at most 5 % high).
        p99_us: 99th percentile [µs] (likewise).
        max_us: largest [µs] (exact).
    """

    count: int
    p50_us: float
    p99_us: float
    max_us: float

    @classmethod
    def empty(cls) -> DurationSummary:
        """No durations recorded."""
        return cls(0, 0.0, 0.0, 0.0)


class DurationHistogram:
    """Counts durations for percentiles; see the module docstring."""

    def __init__(self) -> None:
        size = len(BUCKET_EDGES_NS) + 1
        self._window = [0] * size
        self._total = [0] * size
        self._window_max_ns = 0
        self._total_max_ns = 0

    def record(self, duration_ns: int) -> None:
        """Count one duration [ns] (negative counts as 0)."""
        i = bisect.bisect_right(BUCKET_EDGES_NS, duration_ns)
        self._window[i] += 1
        self._total[i] += 1
        if duration_ns > self._window_max_ns:
            self._window_max_ns = duration_ns
            self._total_max_ns = max(self._total_max_ns, duration_ns)

    def window(self) -> DurationSummary:
        """Summary of the current window."""
        return _summary(list(self._window), self._window_max_ns)

    def total(self) -> DurationSummary:
        """Summary since start."""
        return _summary(list(self._total), self._total_max_ns)

    def take_window(self) -> DurationSummary:
        """Summary of the current window; then start a new one."""
        summary = self.window()
        self._window = [0] * len(self._window)
        self._window_max_ns = 0
        return summary


def _summary(counts: list[int], max_ns: int) -> DurationSummary:
    count = sum(counts)
    if count == 0:
        return DurationSummary.empty()
    return DurationSummary(
        count=count,
        p50_us=_percentile(counts, count, 0.50, max_ns) / 1e3,
        p99_us=_percentile(counts, count, 0.99, max_ns) / 1e3,
        max_us=max_ns / 1e3,
    )


def _percentile(counts: list[int], count: int, q: float, max_ns: int) -> float:
    """Upper edge [ns] of the bucket holding the q-quantile, capped at the maximum."""
    rank = math.ceil(q * count)
    seen = 0
    for i, n in enumerate(counts):
        seen += n
        if seen >= rank:
            edge = BUCKET_EDGES_NS[i] if i < len(BUCKET_EDGES_NS) else max_ns
            return float(min(edge, max_ns))
    return float(max_ns)


#: Upper edges of the period-error histogram buckets [µs]; the last bucket is open.
HISTOGRAM_EDGES_US = (10, 50, 100, 200, 500, 1000, 2000, 5000)


@dataclasses.dataclass(frozen=True)
class PeriodStats:
    """Timing of the scheduler loop.

    Attributes:
        period_ns: nominal period [ns].
        ticks: ticks run.
        overruns: deadlines missed (a tick ended after the next deadline).
        skipped_ticks: periods skipped whole because of overruns (no tick ran in them).
        max_error_us: largest |start - deadline| seen [µs].
        mean_error_us: mean |start - deadline| [µs].
        histogram: counts per bucket of |start - deadline|; bucket i holds errors below
            ``HISTOGRAM_EDGES_US[i]`` µs, the last one the rest.
        max_tick_us: longest tick (stages + update + pack + send) [µs].
        errors: exceptions passed to on_error.
        lateness: start lateness (start - deadline) since start.
        components: duration of each component since start, by name, in loop order.
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
    lateness: DurationSummary = dataclasses.field(default_factory=DurationSummary.empty)
    components: tuple[tuple[str, DurationSummary], ...] = ()
