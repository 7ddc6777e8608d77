"""Monotonic 1-D lookup tables with linear interpolation, e.g. bullet speed -> wheel speed.

A shooter's friction wheels are tuned by firing at several wheel speeds and noting the
bullet speed the referee reports; the table then gives the wheel speed for a wanted
bullet speed. Between points it interpolates linearly; outside them it holds the end
values (it never extrapolates a motor command beyond what was measured).
"""

import bisect
import itertools
import math
from collections.abc import Sequence
from numbers import Real

from rm_base.errors import ConfigError, InputRejectedError


class LookupTable:
    """y = f(x) through points with strictly increasing x and monotonic y.

    Example:
        >>> table = LookupTable([(15.0, 500.0), (30.0, 800.0)])
        >>> table(20.0)
        600.0
    """

    __slots__ = ('_increasing', '_xs', '_ys')

    def __init__(self, points: Sequence[Sequence[float]]) -> None:
        """Build the table.

        Args:
            points: (x, y) pairs, at least two, x strictly increasing; y all non-decreasing
                or all non-increasing.

        Raises:
            ConfigError: If there are fewer than two points, a point is not two finite
                numbers, x is not strictly increasing or y is not monotonic.
        """
        xs: list[float] = []
        ys: list[float] = []
        for index, point in enumerate(points):
            try:
                x, y = point
            except (TypeError, ValueError) as err:
                raise ConfigError(f'lookup point {index} must be (x, y), got {point!r}') from err
            for value in (x, y):
                if isinstance(value, bool) or not isinstance(value, Real):
                    raise ConfigError(f'lookup point {index} must be numbers, got {point!r}')
                if not math.isfinite(value):
                    raise ConfigError(f'lookup point {index} must be finite, got {point!r}')
            xs.append(float(x))
            ys.append(float(y))
        if len(xs) < 2:
            raise ConfigError(f'a lookup table needs at least 2 points, got {len(xs)}')
        for index in range(1, len(xs)):
            if not xs[index] > xs[index - 1]:
                raise ConfigError(
                    f'lookup x must be strictly increasing: point {index} has x={xs[index]!r} '
                    f'after x={xs[index - 1]!r}'
                )
        steps = [b - a for a, b in itertools.pairwise(ys)]
        if any(step < 0.0 for step in steps) and any(step > 0.0 for step in steps):
            raise ConfigError(f'lookup y must be monotonic, got {ys!r}')
        self._xs = tuple(xs)
        self._ys = tuple(ys)
        self._increasing = not any(step < 0.0 for step in steps)

    @classmethod
    def from_columns(cls, xs: Sequence[float], ys: Sequence[float]) -> 'LookupTable':
        """Build the table from a column of x and a column of y (as a YAML config has them).

        Raises:
            ConfigError: If the columns differ in length, or as :class:`LookupTable`.
        """
        if len(xs) != len(ys):
            raise ConfigError(f'lookup columns differ in length: {len(xs)} x and {len(ys)} y')
        return cls(list(zip(xs, ys, strict=True)))

    @property
    def points(self) -> tuple[tuple[float, float], ...]:
        """The (x, y) points, x increasing."""
        return tuple(zip(self._xs, self._ys, strict=True))

    @property
    def increasing(self) -> bool:
        """True if y never decreases with x (a constant table counts as increasing)."""
        return self._increasing

    def __call__(self, x: float) -> float:
        """Return y at x, interpolated linearly, held at the end values outside the table.

        Raises:
            InputRejectedError: If x is NaN or infinite.
        """
        if not math.isfinite(x):
            raise InputRejectedError(f'lookup input must be finite, got {x!r}')
        xs = self._xs
        if x <= xs[0]:
            return self._ys[0]
        if x >= xs[-1]:
            return self._ys[-1]
        upper = bisect.bisect_right(xs, x)  # xs[upper - 1] <= x < xs[upper]
        x0, x1 = xs[upper - 1], xs[upper]
        y0, y1 = self._ys[upper - 1], self._ys[upper]
        return y0 + (y1 - y0) * (x - x0) / (x1 - x0)

    def inverted(self) -> 'LookupTable':
        """Return the table x = f⁻¹(y), e.g. wheel speed -> expected bullet speed.

        Raises:
            ConfigError: If y is not strictly monotonic (a flat part has no inverse).
        """
        pairs = list(zip(self._ys, self._xs, strict=True))
        if not self._increasing:
            pairs.reverse()
        try:
            return LookupTable(pairs)
        except ConfigError as err:
            raise ConfigError(
                f'lookup y must be strictly monotonic to invert, got {self._ys!r}'
            ) from err

    def __repr__(self) -> str:
        return f'LookupTable({list(self.points)!r})'
