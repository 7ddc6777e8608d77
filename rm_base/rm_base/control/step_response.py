"""The four figures of a step response: rise time, overshoot, settling time, steady error.

Definitions (docs/ROBOT.md, "Tuning a joint's loop"), for a response y(t) sampled from
the step at t = 0 from y0 (the response there) towards the target r, step h = r - y0:

- rise time: from y first crossing y0 + 10 % of h to its first crossing 90 %
  (interpolated between samples); None if it never reaches 90 %;
- overshoot: how far the response went beyond r, in % of |h| (0 if never beyond);
- settling time: the time after which y stays within SETTLE_BAND of |h| around r to the
  end of the record; None if it is outside at the end;
- steady-state error: r minus the mean of y over the last TAIL of the record.

Pure arithmetic on the samples; the ROS side is rmcli's (rm_bringup.cli.tune_step).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

#: The settling band, a fraction of the step.
SETTLE_BAND = 0.02
#: The fraction of the record (its end) averaged for the steady-state error.
TAIL = 0.1


class StepError(ValueError):
    """A record that has no step response in it (too short, or no step)."""


@dataclass(frozen=True)
class StepFigures:
    """The four figures (see the module docstring); times [s], error in y's unit."""

    rise_time: float | None
    overshoot_pct: float
    settling_time: float | None
    steady_state_error: float


def step_figures(t: Sequence[float], y: Sequence[float], target: float) -> StepFigures:
    """The figures of samples (t [s] from the step, y) towards target.

    Raises:
        StepError: fewer than 3 samples, times not increasing, a non-finite value, or
            a step of zero.
    """
    if len(t) != len(y) or len(t) < 3:
        raise StepError(f'a step response needs 3 or more samples, got {len(t)}')
    if not all(math.isfinite(v) for v in (*t, *y, target)):
        raise StepError('a sample or the target is not a finite number')
    if any(b <= a for a, b in itertools.pairwise(t)):
        raise StepError('sample times must increase')
    y0 = y[0]
    h = target - y0
    if h == 0.0:
        raise StepError(f'no step: the response starts at the target {target:g}')
    progress = [(v - y0) / h for v in y]  # 0 at the start, 1 at the target
    t10 = _first_crossing(t, progress, 0.1)
    t90 = _first_crossing(t, progress, 0.9)
    rise = None if t10 is None or t90 is None else t90 - t10
    overshoot = max(0.0, max(progress) - 1.0) * 100.0
    settled = None
    for i in range(len(y) - 1, -1, -1):
        if abs(progress[i] - 1.0) > SETTLE_BAND:
            settled = t[i + 1] - t[0] if i + 1 < len(y) else None
            break
    else:
        settled = 0.0
    tail = [v for ti, v in zip(t, y, strict=True) if ti >= t[-1] - TAIL * (t[-1] - t[0])]
    return StepFigures(rise, overshoot, settled, target - sum(tail) / len(tail))


def _first_crossing(t: Sequence[float], progress: Sequence[float], level: float) -> float | None:
    """When progress first reaches level (linear between samples), from t[0]; or None."""
    for i in range(1, len(progress)):
        a, b = progress[i - 1], progress[i]
        if a < level <= b:
            return t[i - 1] + (level - a) / (b - a) * (t[i] - t[i - 1]) - t[0]
    return 0.0 if progress[0] >= level else None
