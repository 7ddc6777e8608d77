"""Gyro bias at standstill: the mean rate of a still sensor over a window (no ROS, no I/O).

A sensor that does not turn should read 0 rad/s; what it reads instead, averaged, is its
bias. The plugin keeps the raw rates of the last ``duration`` seconds (:class:`GyroWindow`)
and, when asked, takes their mean as the bias (:func:`bias_at_rest`) only if they show a
sensor at rest: enough samples over the whole window, a spread no larger than the
sensor's noise, and a mean small enough to be a bias rather than a slow turn.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass

import numpy as np
from rm_base.errors import InputRejectedError

_NS_PER_S = 1_000_000_000

Vector3 = tuple[float, float, float]


class NotAtRestError(InputRejectedError):
    """The samples do not show a sensor at rest (or are too few to tell)."""


@dataclass(frozen=True)
class RestLimits:
    """What counts as at rest.

    Attributes:
        duration_s: the window [s]; the samples must cover most of it (90 %).
        max_rate: largest |mean| per axis taken as bias, not motion [rad/s].
        max_spread: largest standard deviation per axis of a still sensor [rad/s].
        min_samples: fewest samples to average.
    """

    duration_s: float
    max_rate: float
    max_spread: float
    min_samples: int = 20


class GyroWindow:
    """The rates of the last duration_s seconds, by stamp (one thread adds, any reads a copy)."""

    def __init__(self, duration_s: float) -> None:
        self._span_ns = round(duration_s * _NS_PER_S)
        self._samples: collections.deque[tuple[int, Vector3]] = collections.deque()

    def add(self, stamp_ns: int, rate: Vector3) -> None:
        """Add one sample [rad/s] taken at stamp_ns; drop those older than the window."""
        samples = self._samples
        samples.append((stamp_ns, rate))
        oldest = stamp_ns - self._span_ns
        while samples[0][0] < oldest:
            samples.popleft()

    def clear(self) -> None:
        """Forget every sample (the sensor stopped streaming)."""
        self._samples.clear()

    def snapshot(self) -> list[tuple[int, Vector3]]:
        """A copy of the samples, oldest first."""
        return list(self._samples)


def bias_at_rest(samples: list[tuple[int, Vector3]], limits: RestLimits) -> Vector3:
    """The mean rate of samples, if they show a sensor at rest.

    Raises:
        NotAtRestError: too few samples, a window not covered, a spread above the noise
            limit, or a mean too large for a bias; the message gives the numbers.
    """
    n = len(samples)
    span_s = (samples[-1][0] - samples[0][0]) / _NS_PER_S if n else 0.0
    if n < limits.min_samples or span_s < 0.9 * limits.duration_s:
        raise NotAtRestError(
            f'not enough IMU data: {n} samples over {span_s:.2f} s, need '
            f'{limits.min_samples} over {limits.duration_s:g} s'
        )
    rates = np.array([rate for _, rate in samples], dtype=float)
    mean, spread = rates.mean(axis=0), rates.std(axis=0)
    if float(spread.max()) > limits.max_spread:
        raise NotAtRestError(
            f'moving: the rate varies by {float(spread.max()):.4f} rad/s (1 sigma, at rest '
            f'at most {limits.max_spread:g}): keep the IMU still'
        )
    if float(np.abs(mean).max()) > limits.max_rate:
        raise NotAtRestError(
            f'turning: mean rate {float(np.abs(mean).max()):.4f} rad/s, more than a bias '
            f'(at most {limits.max_rate:g}): keep the IMU still'
        )
    x, y, z = mean.tolist()
    return (x, y, z)
