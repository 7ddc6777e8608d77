"""Slew-rate (ramp) limiting of velocity commands, with launch, normal and brake phases.

Each axis (e.g. vx [m/s], vy [m/s], wz [rad/s]) moves its value towards its target with an
acceleration limit chosen from the state at the start of the step:

- **brake** when slowing down: ``|target| < |current|``, or target and current have
  opposite signs. A sign change brakes to zero first and spends the rest of the step
  accelerating from zero (launch limit), so reversing is never faster than stop-then-go.
- **launch** when speeding up from ``|current| < launch_speed`` (a standing start, where
  wheels slip most easily).
- **normal** when speeding up from ``|current| >= launch_speed``.

An acceleration of None or ``inf`` leaves that phase unlimited; an axis whose limits are
None passes its target straight through.
"""

import math
from collections.abc import Sequence
from dataclasses import dataclass

from rm_base.control.validation import require_non_negative, require_positive
from rm_base.errors import ConfigError, InputRejectedError


@dataclass(frozen=True, slots=True)
class RampLimits:
    """Acceleration limits of one axis.

    u is the unit of the axis (m/s for vx, rad/s for wz), so u/s is m/s² or rad/s².

    Attributes:
        launch_acceleration: Limit when speeding up from |current| < launch_speed
            [u/s], > 0; None or inf for no limit.
        normal_acceleration: Limit when speeding up from |current| >= launch_speed
            [u/s], > 0; None or inf for no limit.
        brake_acceleration: Limit when slowing down or reversing [u/s], > 0; None or inf
            for no limit.
        launch_speed: Below this |current| [u] speeding up uses the launch limit, >= 0.
    """

    launch_acceleration: float | None = None
    normal_acceleration: float | None = None
    brake_acceleration: float | None = None
    launch_speed: float = 0.0

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ('launch_acceleration', 'normal_acceleration', 'brake_acceleration'):
            value = getattr(self, name)
            # None is kept as the spelling of "unlimited"; inf is normalised to it.
            checked = None if value is None else require_positive(owner, name, value, finite=False)
            object.__setattr__(self, name, None if checked == math.inf else checked)
        object.__setattr__(
            self, 'launch_speed', require_non_negative(owner, 'launch_speed', self.launch_speed)
        )


def _towards(current: float, goal: float, max_step: float | None) -> float:
    if max_step is None:
        return goal
    if goal > current:
        return min(goal, current + max_step)
    return max(goal, current - max_step)


def ramp_step(current: float, target: float, limits: RampLimits | None, dt: float) -> float:
    """Return the value one step of dt after current, on its way to target.

    Args:
        current: Value now [u].
        target: Value wanted [u].
        limits: Acceleration limits of this axis, or None for no limit.
        dt: Step [s], > 0.

    Returns:
        The new value [u]; it never passes target.
    """
    if limits is None or target == current:
        return target
    if current != 0.0 and (target * current < 0.0 or abs(target) < abs(current)):
        brake = limits.brake_acceleration
        if target * current >= 0.0:
            return _towards(current, target, None if brake is None else brake * dt)
        # Reversing: brake to zero, then launch with whatever time is left of the step.
        if brake is not None:
            if abs(current) >= brake * dt:
                return _towards(current, 0.0, brake * dt)
            dt -= abs(current) / brake
        current = 0.0
    if abs(current) < limits.launch_speed:
        acceleration = limits.launch_acceleration
    else:
        acceleration = limits.normal_acceleration
    return _towards(current, target, None if acceleration is None else acceleration * dt)


class RampLimiter:
    """Per-axis ramp limiting of a velocity vector, e.g. (vx, vy, wz).

    The limiter starts at rest (all zero), as a chassis does when enabled.
    """

    __slots__ = ('_limits', '_values')

    def __init__(self, limits: Sequence[RampLimits | None]) -> None:
        """Create a limiter with one entry per axis.

        Args:
            limits: Limits of each axis, in axis order; None leaves an axis unlimited.

        Raises:
            ConfigError: If limits is empty or holds something other than RampLimits/None.
        """
        limits = tuple(limits)
        if not limits:
            raise ConfigError('RampLimiter needs at least one axis')
        for index, axis in enumerate(limits):
            if axis is not None and not isinstance(axis, RampLimits):
                raise ConfigError(
                    f'RampLimiter axis {index} must be RampLimits or None, got {axis!r}'
                )
        self._limits = limits
        self._values = (0.0,) * len(limits)

    @property
    def values(self) -> tuple[float, ...]:
        """The limited values after the last update [u per axis]."""
        return self._values

    def reset(self, values: Sequence[float] | None = None) -> None:
        """Restart from values (default all zero), e.g. the measured velocity.

        Raises:
            InputRejectedError: If values has the wrong length or a non-finite entry.
        """
        self._values = (0.0,) * len(self._limits) if values is None else self._check(values)

    def update(self, targets: Sequence[float], dt: float) -> tuple[float, ...]:
        """Step every axis towards its target and return the limited values.

        Args:
            targets: Target per axis [u], same order as the limits.
            dt: Time since the previous update [s], finite and > 0.

        Returns:
            The limited values [u per axis].

        Raises:
            InputRejectedError: If dt <= 0 or not finite, or targets has the wrong length
                or a NaN/inf entry. The state is left as it was.
        """
        if not 0.0 < dt < math.inf:
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        targets = self._check(targets)
        self._values = tuple(
            ramp_step(current, target, limits, dt)
            for current, target, limits in zip(self._values, targets, self._limits, strict=True)
        )
        return self._values

    def _check(self, values: Sequence[float]) -> tuple[float, ...]:
        values = tuple(float(value) for value in values)
        if len(values) != len(self._limits):
            raise InputRejectedError(f'expected {len(self._limits)} ramp values, got {len(values)}')
        if not all(map(math.isfinite, values)):
            raise InputRejectedError(f'ramp values must be finite, got {values!r}')
        return values
