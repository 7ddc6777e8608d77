"""Positional PID controller for scalar loops (motor speed, gimbal angle) run at up to 1 kHz.

Each :meth:`Pid.update` computes, with ``e = setpoint - measurement`` (wrapped to the
shortest way round in angle mode, then zeroed inside the deadband):

- ``P = kp * e``
- ``I += ki * (e + e_prev) / 2 * dt`` (trapezoid), only while ``|e| < integral_separation``,
  then clamped to ``±min(integral_limit, output_limit)``. The I term is stored already
  multiplied by ki, so retuning ki does not make the output jump.
- ``D = -kd * dm/dt`` on the measurement, not the error, so a setpoint step does not kick
  the output; ``dm/dt`` optionally goes through a first-order low-pass (``derivative_tau_s``).
- ``output = clamp(P + I + D, ±output_limit)``.

``update`` is the hot path (about ten motors at 1 kHz from one Python thread): it works on
plain floats and allocates nothing but the float results.
"""

import math
from dataclasses import dataclass

from rm_base.control.validation import require_non_negative, require_positive
from rm_base.errors import ConfigError, InputRejectedError

_INF = math.inf
_PI = math.pi
_TAU = 2.0 * math.pi


@dataclass(frozen=True, slots=True)
class PidGains:
    """Gains and limits of a :class:`Pid`; validated at construction.

    Error units are those of the setpoint (rad, rad/s, ...); output units are those of
    the actuator command (A, N·m, ...). ``inf`` switches a limit off.

    Attributes:
        kp: Proportional gain [output / error], >= 0.
        ki: Integral gain [output / (error·s)], >= 0.
        kd: Derivative gain [output / (error/s)], >= 0.
        output_limit: Output clamped to ±output_limit [output], > 0.
        integral_limit: I term clamped to ±integral_limit [output], >= 0. The output limit
            also bounds it, so the default never lets the I term wind up past the output.
        integral_separation: Integrate only while |error| < this [error], > 0.
        deadband: |error| <= deadband counts as zero error [error], >= 0, finite.
        derivative_tau_s: Time constant of the low-pass on the measured rate [s]; 0 means
            unfiltered.
        angle_mode: Error (and measured rate) wrapped to [-pi, pi), so a gimbal turns the
            shortest way round; setpoint and measurement in rad.
    """

    kp: float = 0.0
    ki: float = 0.0
    kd: float = 0.0
    output_limit: float = _INF
    integral_limit: float = _INF
    integral_separation: float = _INF
    deadband: float = 0.0
    derivative_tau_s: float = 0.0
    angle_mode: bool = False

    def __post_init__(self) -> None:
        owner = type(self).__name__
        checked = {
            'kp': require_non_negative(owner, 'kp', self.kp),
            'ki': require_non_negative(owner, 'ki', self.ki),
            'kd': require_non_negative(owner, 'kd', self.kd),
            'output_limit': require_positive(
                owner, 'output_limit', self.output_limit, finite=False
            ),
            'integral_limit': require_non_negative(
                owner, 'integral_limit', self.integral_limit, finite=False
            ),
            'integral_separation': require_positive(
                owner, 'integral_separation', self.integral_separation, finite=False
            ),
            'deadband': require_non_negative(owner, 'deadband', self.deadband),
            'derivative_tau_s': require_non_negative(
                owner, 'derivative_tau_s', self.derivative_tau_s
            ),
        }
        for name, value in checked.items():
            object.__setattr__(self, name, value)
        # A YAML 'false' string or a 0/1 must not silently pick a mode.
        if not isinstance(self.angle_mode, bool):
            raise ConfigError(f'{owner}.angle_mode must be a bool, got {self.angle_mode!r}')


class Pid:
    """Positional PID with trapezoidal integral and derivative on measurement.

    The first update after construction or :meth:`reset` has no derivative (no previous
    measurement) and integrates its error as if it had been constant over ``dt``.

    Example:
        >>> pid = Pid(PidGains(kp=2.0, output_limit=10.0))
        >>> pid.update(setpoint=1.0, measurement=0.5, dt=0.001)
        1.0
    """

    __slots__ = (
        '_angle_mode',
        '_d_rate',
        '_d_term',
        '_deadband',
        '_gains',
        '_i_limit',
        '_i_term',
        '_kd',
        '_ki',
        '_kp',
        '_output',
        '_output_limit',
        '_p_term',
        '_prev_error',
        '_prev_measurement',
        '_separation',
        '_tau',
    )

    def __init__(self, gains: PidGains) -> None:
        """Create a controller at rest (zero integral, no history).

        Args:
            gains: Gains and limits.
        """
        self._i_term = 0.0
        self.gains = gains
        self.reset()

    @property
    def gains(self) -> PidGains:
        """Current gains. Setting them keeps the state (for live tuning), clamping I."""
        return self._gains

    @gains.setter
    def gains(self, gains: PidGains) -> None:
        if not isinstance(gains, PidGains):
            raise TypeError(f'gains must be a PidGains, got {type(gains).__name__}')
        self._gains = gains
        # Unpacked into slots: attribute access on the dataclass costs more per update.
        self._kp = gains.kp
        self._ki = gains.ki
        self._kd = gains.kd
        self._output_limit = gains.output_limit
        self._i_limit = min(gains.integral_limit, gains.output_limit)
        self._separation = gains.integral_separation
        self._deadband = gains.deadband
        self._tau = gains.derivative_tau_s
        self._angle_mode = gains.angle_mode
        self._i_term = max(-self._i_limit, min(self._i_limit, self._i_term))

    def reset(self) -> None:
        """Forget integral, derivative filter and history (call on enable and disable)."""
        self._i_term = 0.0
        self._p_term = 0.0
        self._d_term = 0.0
        self._output = 0.0
        self._d_rate = 0.0
        self._prev_error: float | None = None
        self._prev_measurement: float | None = None

    def update(self, setpoint: float, measurement: float, dt: float) -> float:
        """Advance the controller by one period and return the new output.

        Args:
            setpoint: Desired value [error units; rad in angle mode].
            measurement: Measured value, same units as setpoint.
            dt: Time since the previous update [s], finite and > 0.

        Returns:
            The output, within ±output_limit [output units].

        Raises:
            InputRejectedError: If dt <= 0, or any argument is NaN or infinite. The state
                is left as it was.
        """
        if not 0.0 < dt < _INF:  # also false for NaN
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        if not (math.isfinite(setpoint) and math.isfinite(measurement)):
            raise InputRejectedError(
                f'setpoint and measurement must be finite, got {setpoint!r}, {measurement!r}'
            )

        error = setpoint - measurement
        if self._angle_mode and not -_PI <= error < _PI:
            error = math.remainder(error, _TAU)
            if error >= _PI:
                error -= _TAU
        if -self._deadband <= error <= self._deadband:
            error = 0.0

        prev_error = self._prev_error
        separation = self._separation
        if -separation < error < separation:
            # Entering the integration band from outside: the previous error was never
            # meant to be integrated, so use the current one for both trapezoid ends.
            if prev_error is None or not -separation < prev_error < separation:
                prev_error = error
            i_term = self._i_term + self._ki * 0.5 * (error + prev_error) * dt
            i_limit = self._i_limit
            if i_term > i_limit:
                i_term = i_limit
            elif i_term < -i_limit:
                i_term = -i_limit
            self._i_term = i_term

        prev_measurement = self._prev_measurement
        if prev_measurement is not None:
            delta = measurement - prev_measurement
            if self._angle_mode and not -_PI <= delta < _PI:
                delta = math.remainder(delta, _TAU)
            rate = delta / dt
            if self._tau > 0.0:
                # Exact discretisation of a first-order low-pass, valid for any dt.
                rate = self._d_rate - (rate - self._d_rate) * math.expm1(-dt / self._tau)
            self._d_rate = rate

        p_term = self._kp * error
        d_term = -self._kd * self._d_rate
        output = p_term + self._i_term + d_term
        limit = self._output_limit
        if output > limit:
            output = limit
        elif output < -limit:
            output = -limit

        self._prev_error = error
        self._prev_measurement = measurement
        self._p_term = p_term
        self._d_term = d_term
        self._output = output
        return output

    @property
    def output(self) -> float:
        """Output of the last update (0 after reset) [output units]."""
        return self._output

    @property
    def p_term(self) -> float:
        """P term of the last update [output units]."""
        return self._p_term

    @property
    def i_term(self) -> float:
        """Current I term (already multiplied by ki) [output units]."""
        return self._i_term

    @property
    def d_term(self) -> float:
        """D term of the last update [output units]."""
        return self._d_term
