"""Incremental (velocity-form) PID with an optional tracking differentiator on the setpoint.

This is the form RoboMaster firmware uses for motor speed loops. Each update adds an
increment to the held output, with ``e = r - measurement`` where ``r`` is the setpoint,
or the TD's smoothed copy of it:

- ``du = kp * (e - e_prev) + ki * e * dt + kd * (de/dt - de/dt_prev)``
- ``output = clamp(output + du, ±output_limit)``

The increments are those of a positional PID (P, rectangle-rule I, D on the error), so
the integral lives in the output itself; clamping the output therefore also stops it
winding up. The state starts at rest: the first update acts as if the previous error was
zero, but has no derivative (no kick from the first error).

In angle mode (a gimbal or heading loop) the error is wrapped to [-pi, pi) so the loop
turns the short way, its rate is taken from the wrapped change, and the TD follows the
setpoint the short way round from where it is.
"""

import math
from dataclasses import dataclass

from rm_base.control.tracking_differentiator import TdParams, TrackingDifferentiator
from rm_base.control.validation import require_non_negative, require_positive
from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry.angles import wrap_to_pi


@dataclass(frozen=True, slots=True)
class IncrementalPidGains:
    """Gains and output limit of an :class:`IncrementalPid`; validated at construction.

    Attributes:
        kp: Proportional gain [output / error], >= 0.
        ki: Integral gain [output / (error·s)], >= 0.
        kd: Derivative gain [output / (error/s)], >= 0.
        output_limit: Output clamped to ±output_limit [output], > 0 (inf: no limit).
        angle_mode: The error is an angle [rad]: wrapped to [-pi, pi).
    """

    kp: float = 0.0
    ki: float = 0.0
    kd: float = 0.0
    output_limit: float = math.inf
    angle_mode: bool = False

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ('kp', 'ki', 'kd'):
            object.__setattr__(self, name, require_non_negative(owner, name, getattr(self, name)))
        object.__setattr__(
            self,
            'output_limit',
            require_positive(owner, 'output_limit', self.output_limit, finite=False),
        )
        if not isinstance(self.angle_mode, bool):
            raise ConfigError(f'{owner}.angle_mode must be a bool, got {self.angle_mode!r}')


class IncrementalPid:
    """Incremental PID; see the module docstring.

    With ``setpoint_td`` the setpoint first goes through a :class:`TrackingDifferentiator`,
    which starts at the first measurement after each reset, so a large setpoint step
    becomes an acceleration-limited ramp from where the plant is.
    """

    __slots__ = (
        '_d_prev',
        '_e_prev',
        '_gains',
        '_last_increment',
        '_output',
        '_td',
        '_td_started',
    )

    def __init__(self, gains: IncrementalPidGains, setpoint_td: TdParams | None = None) -> None:
        """Create a controller at rest.

        Args:
            gains: Gains and output limit.
            setpoint_td: Parameters of the TD on the setpoint, or None for none.
        """
        if not isinstance(gains, IncrementalPidGains):
            raise TypeError(f'gains must be an IncrementalPidGains, got {type(gains).__name__}')
        self._gains = gains
        self._td = None if setpoint_td is None else TrackingDifferentiator(setpoint_td)
        self.reset()

    @property
    def gains(self) -> IncrementalPidGains:
        """Gains and output limit."""
        return self._gains

    def reset(self) -> None:
        """Zero the output and forget the error history and the TD state."""
        self._output = 0.0
        self._last_increment = 0.0
        self._e_prev = 0.0
        self._d_prev: float | None = None
        self._td_started = False

    def update(self, setpoint: float, measurement: float, dt: float) -> float:
        """Advance one period and return the new output.

        Args:
            setpoint: Desired value [error units].
            measurement: Measured value, same units.
            dt: Time since the previous update [s], finite and > 0.

        Returns:
            The output after this increment, within ±output_limit [output units].

        Raises:
            InputRejectedError: If dt <= 0, or any argument is NaN or infinite. The state
                is left as it was.
        """
        if not 0.0 < dt < math.inf:
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        if not (math.isfinite(setpoint) and math.isfinite(measurement)):
            raise InputRejectedError(
                f'setpoint and measurement must be finite, got {setpoint!r}, {measurement!r}'
            )
        g = self._gains
        angle = g.angle_mode
        td = self._td
        if td is not None:
            if not self._td_started:
                td.reset(measurement)
                self._td_started = True
            tracked = td.value
            if angle and tracked is not None:
                setpoint = tracked + wrap_to_pi(setpoint - tracked)
            setpoint = td.update(setpoint, dt)

        error = setpoint - measurement
        if angle:
            error = wrap_to_pi(error)
        d_prev = self._d_prev
        if d_prev is None:
            rate = d_prev = 0.0
        else:
            change = error - self._e_prev
            rate = (wrap_to_pi(change) if angle else change) / dt
        increment = g.kp * (error - self._e_prev) + g.ki * error * dt + g.kd * (rate - d_prev)
        output = self._output + increment
        limit = g.output_limit
        if output > limit:
            output = limit
        elif output < -limit:
            output = -limit

        self._e_prev = error
        self._d_prev = rate
        self._last_increment = increment
        self._output = output
        return output

    @property
    def output(self) -> float:
        """Output after the last update (0 after reset) [output units]."""
        return self._output

    @property
    def last_increment(self) -> float:
        """Increment computed by the last update, before the output clamp [output units]."""
        return self._last_increment

    @property
    def tracked_setpoint(self) -> float | None:
        """The TD's smoothed setpoint, or None without a TD or before the first update."""
        if self._td is None or not self._td_started:
            return None
        return self._td.value
