"""Small statistics helpers: percentiles of samples and min/median/max across runs."""

from __future__ import annotations

import math
import statistics
from collections.abc import Iterable, Sequence


def percentile(sorted_values: Sequence[float], q: float) -> float:
    """The q-th percentile (0..100) of already sorted values, linear interpolation.

    Same definition as numpy's default ('linear'); NaN for no values.
    """
    n = len(sorted_values)
    if n == 0:
        return math.nan
    if n == 1:
        return float(sorted_values[0])
    pos = (n - 1) * q / 100.0
    lo = math.floor(pos)
    hi = min(lo + 1, n - 1)
    frac = pos - lo
    return float(sorted_values[lo]) * (1.0 - frac) + float(sorted_values[hi]) * frac


def summary(values: Iterable[float]) -> dict[str, float]:
    """n, mean, p50, p90, p99, p99.9 and max of the values (NaN where empty)."""
    data = sorted(values)
    n = len(data)
    return {
        'n': n,
        'mean': statistics.fmean(data) if n else math.nan,
        'p50': percentile(data, 50),
        'p90': percentile(data, 90),
        'p99': percentile(data, 99),
        'p999': percentile(data, 99.9),
        'max': float(data[-1]) if n else math.nan,
    }


def spread(values: Iterable[float | None]) -> tuple[float, float, float] | None:
    """(min, median, max) of the finite values, or None if there are none."""
    finite = [float(v) for v in values if v is not None and math.isfinite(v)]
    if not finite:
        return None
    return min(finite), statistics.median(finite), max(finite)


def linear_fit(xs: Sequence[float], ys: Sequence[float]) -> tuple[float, float]:
    """Least-squares line y = slope * x + intercept; (NaN, NaN) with fewer than 2 points."""
    if len(xs) < 2:
        return math.nan, math.nan
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    if sxx == 0:
        return math.nan, math.nan
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sxx
    return slope, my - slope * mx
