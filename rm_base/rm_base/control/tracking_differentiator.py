"""Han's tracking differentiator (TD): a smooth, acceleration-limited copy of a signal.

The discrete TD of Han Jingqing's ADRC, as RoboMaster firmware runs it on setpoints::

    fh = fhan(x1 - v, x2, r, h0)
    x1 += h * x2
    x2 += h * fh

``x1`` tracks the input ``v`` as fast as an acceleration limit ``r`` allows (time-optimal
for a double integrator, so a step of size A settles in about ``2 * sqrt(A / r)`` without
overshoot) and ``x2`` is its derivative, without differentiating noise. ``h`` is the step
(the update's dt) and ``h0`` the filter factor; ``h0 >= h`` (default ``h0 = h``) avoids
chattering near the target, larger ``h0`` filters more.
"""

import math
from dataclasses import dataclass

from rm_base.control.validation import require_positive
from rm_base.errors import InputRejectedError


def fhan(x1: float, x2: float, r: float, h: float) -> float:
    """Han's time-optimal synthesis function for a discrete double integrator.

    Args:
        x1: Position error, tracked value minus target [u].
        x2: Velocity of the tracked value [u/s].
        r: Acceleration limit (Han's speed factor) [u/s²], > 0.
        h: Filter factor (Han's h0) [s], > 0.

    Returns:
        The acceleration to apply [u/s²], within ±r; it drives (x1, x2) to (0, 0).
    """
    d = r * h
    d0 = h * d
    y = x1 + h * x2
    if abs(y) > d0:
        a = x2 + math.copysign(0.5 * (math.sqrt(d * d + 8.0 * r * abs(y)) - d), y)
    else:
        a = x2 + y / h
    if abs(a) > d:
        return -math.copysign(r, a)
    return -r * a / d


@dataclass(frozen=True, slots=True)
class TdParams:
    """Parameters of a :class:`TrackingDifferentiator`.

    Attributes:
        acceleration_limit: Han's r: the largest |d²x1/dt²| [u/s²], > 0. Larger tracks
            faster.
        filter_factor_s: Han's h0 [s], > 0, or None to use each update's dt.
    """

    acceleration_limit: float
    filter_factor_s: float | None = None

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(
            self,
            'acceleration_limit',
            require_positive(owner, 'acceleration_limit', self.acceleration_limit),
        )
        if self.filter_factor_s is not None:
            object.__setattr__(
                self,
                'filter_factor_s',
                require_positive(owner, 'filter_factor_s', self.filter_factor_s),
            )


class TrackingDifferentiator:
    """Discrete Han TD; see the module docstring.

    Unless :meth:`reset` gave a start value, the first update starts at its target (no
    transient), as a filter initialises on its first sample.
    """

    __slots__ = ('_h0', '_r', '_x1', '_x2')

    def __init__(self, params: TdParams) -> None:
        """Create a TD that initialises on its first target.

        Args:
            params: Acceleration limit and filter factor.
        """
        if not isinstance(params, TdParams):
            raise TypeError(f'params must be a TdParams, got {type(params).__name__}')
        self._r = params.acceleration_limit
        self._h0 = params.filter_factor_s
        self.reset()

    def reset(self, value: float | None = None, derivative: float = 0.0) -> None:
        """Restart the TD.

        Args:
            value: Start value of x1 [u], or None to start at the next target.
            derivative: Start value of x2 [u/s] (ignored when value is None).

        Raises:
            InputRejectedError: If value or derivative is NaN or infinite.
        """
        if value is not None and not (math.isfinite(value) and math.isfinite(derivative)):
            raise InputRejectedError(
                f'TD start value and derivative must be finite, got {value!r}, {derivative!r}'
            )
        self._x1 = value
        self._x2 = 0.0 if value is None else derivative

    def update(self, target: float, dt: float) -> float:
        """Advance one step towards target and return the tracked value x1.

        Args:
            target: Input signal v [u].
            dt: Step h [s], finite and > 0.

        Returns:
            x1 after the step [u].

        Raises:
            InputRejectedError: If dt <= 0, or target or dt is NaN or infinite.
        """
        if not 0.0 < dt < math.inf:
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        if not math.isfinite(target):
            raise InputRejectedError(f'TD target must be finite, got {target!r}')
        x1 = self._x1
        if x1 is None:
            self._x1 = target
            return target
        x2 = self._x2
        fh = fhan(x1 - target, x2, self._r, dt if self._h0 is None else self._h0)
        self._x1 = x1 + dt * x2
        self._x2 = x2 + dt * fh
        return self._x1

    @property
    def value(self) -> float | None:
        """Tracked value x1 [u], or None before the first update after a bare reset."""
        return self._x1

    @property
    def derivative(self) -> float:
        """Derivative estimate x2 [u/s]."""
        return self._x2
