"""Physics of one geared brushless motor with its driver: pure, SI, deterministic.

The model is one rigid rotational degree of freedom written on the rotor side (before the
gearbox). The rotor carries its own inertia plus the load inertia reflected through the
gearbox (``J = J_rotor + J_load / G**2``). Torques on the rotor:

* motor torque ``kt_r * I``, the current ``I`` being set by the driver's control law and
  limited by the driver's current limit and by the supply voltage against back-EMF:
  ``(-V - ke_r*w) / R <= I <= (V - ke_r*w) / R``;
* viscous friction ``-b_r * w`` and Coulomb friction of magnitude ``c_r`` (which also holds
  the rotor still while the other torques are smaller: stiction);
* an external torque (gravity, a load) and a jam (extra Coulomb friction or a locked rotor).

Rotor-side constants come from the output-shaft values users configure:
``kt_r = Kt / G``, ``ke_r = Ke / G``, ``b_r = b / G**2``, ``c_r = c / G``; the output angle is
``rotor_angle / G``, the output torque ``G * kt_r * I = Kt * I``.

Integration is backward (implicit) Euler for everything linear in the new velocity: the
driver's stiffness and damping (MIT kp/kd, the back-EMF of a voltage-mode driver), viscous
and Coulomb friction. Only the external torque is explicit. That keeps the model stable at
dt = 1 ms for any gain a real motor accepts, and never adds energy; the price is a little
numerical damping, which is well inside what real friction does anyway.

The winding temperature is a first-order thermal model: it heats with ``I**2 * R`` and
cools towards ambient through a thermal resistance.
"""

from __future__ import annotations

import math
from enum import Enum
from typing import NamedTuple

from rm_base.sim_devices.motor_params import MotorParams

#: Rotor encoder counts per rotor revolution on DJI motors.
DJI_ENCODER_COUNTS = 8192


class DriveMode(Enum):
    """How the driver sets the winding current."""

    CURRENT = 'current'  # current loop: I follows the commanded current
    VOLTAGE = 'voltage'  # open voltage: I = (V_cmd - Ke*w) / R (GM6020 voltage mode)
    IMPEDANCE = 'impedance'  # MIT law on the motor: kp*(p - q) + kd*(v - dq) + t_ff


class _StepTerms(NamedTuple):
    """Rotor-side constants of one step (SI)."""

    dt: float
    kt: float
    inertia: float
    viscous: float
    coulomb: float
    explicit: float


def _finite(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f'{name} must be finite, got {value}')
    return value


class MotorModel:
    """State and dynamics of one motor; advance it with :meth:`step`.

    The driver's control law is set with one of :meth:`command_current`,
    :meth:`command_voltage` or :meth:`command_impedance` and stays in force until changed.
    Fault hooks: :attr:`locked` (locked rotor), :attr:`brake_torque` (extra Coulomb friction,
    e.g. a jammed feeder), :attr:`external_torque` (signed load, e.g. gravity) and
    :attr:`temperature_override` (forced winding temperature).

    Attributes:
        rotor_angle: rotor angle relative to the stator, unwrapped [rad].
        rotor_velocity: [rad/s], rotor side.
        current: winding (torque) current after the driver's limits [A].
        temperature: winding temperature [°C].
        locked: the rotor cannot turn (the current still flows and heats the winding).
        brake_torque: extra Coulomb friction at the output [N·m], >= 0.
        external_torque: signed torque applied to the output shaft [N·m].
        temperature_override: if not None, the temperature is held at this value [°C].
    """

    def __init__(self, params: MotorParams, *, angle: float = 0.0, velocity: float = 0.0):
        """Create a motor at rest (or at the given output angle [rad] and speed [rad/s])."""
        self.params = params  # also derives the per-step constants (setter)
        self.rotor_angle = _finite('angle', angle) * params.gear_ratio
        self.rotor_velocity = _finite('velocity', velocity) * params.gear_ratio
        self.current = 0.0
        self.temperature = params.ambient_temperature
        self.locked = False
        self.brake_torque = 0.0
        self.external_torque = 0.0
        self.temperature_override: float | None = None
        self._mode = DriveMode.CURRENT
        # Control law in current units, rotor side: I = i0 - ki * angle - di * velocity.
        self._i0 = 0.0
        self._ki = 0.0
        self._di = 0.0

    @property
    def params(self) -> MotorParams:
        """Physical constants; setting them derives the per-step constants again."""
        return self._params

    @params.setter
    def params(self, params: MotorParams) -> None:
        g = params.gear_ratio
        self._params = params
        # Rotor-side constants of every step, computed as step() did each time: stepping at
        # 1 kHz for nine motors, the attribute reads and divisions were a good part of it.
        self._kt = params.torque_constant / g
        self._ke = params.back_emf_constant / g
        self._inertia = params.inertia
        self._viscous = params.viscous_friction / g**2
        self._thermal_rc = params.thermal_resistance * params.thermal_capacitance

    # -- commands ------------------------------------------------------------------------

    @property
    def mode(self) -> DriveMode:
        """The driver's control law in force."""
        return self._mode

    def command_current(self, current: float) -> None:
        """Drive a current [A] (clamped to the driver's limits); positive turns forward."""
        self._mode = DriveMode.CURRENT
        self._i0, self._ki, self._di = _finite('current', current), 0.0, 0.0

    def command_voltage(self, voltage: float) -> None:
        """Apply a winding voltage [V] (clamped to ±supply): I = (V - Ke*w) / R."""
        p = self.params
        volts = max(-p.supply_voltage, min(p.supply_voltage, _finite('voltage', voltage)))
        self._mode = DriveMode.VOLTAGE
        self._i0 = volts / p.resistance
        self._ki = 0.0
        self._di = p.back_emf_constant / p.gear_ratio / p.resistance

    def command_impedance(
        self,
        position: float,
        velocity: float,
        kp: float,
        kd: float,
        torque: float,
        *,
        position_offset: float = 0.0,
    ) -> None:
        """Set the MIT law, all at the output shaft: tau = kp*(p - q) + kd*(v - dq) + t_ff.

        Args:
            position: target position p [rad], in the frame of ``q = angle - position_offset``.
            velocity: target velocity v [rad/s].
            kp: stiffness [N·m/rad], >= 0.
            kd: damping [N·m·s/rad], >= 0.
            torque: feed-forward t_ff [N·m].
            position_offset: output angle [rad] at which q reads 0 (the motor's zero).

        Raises:
            ValueError: a non-finite value or a negative gain.
        """
        p = self.params
        kp, kd = _finite('kp', kp), _finite('kd', kd)
        if kp < 0.0 or kd < 0.0:
            raise ValueError(f'kp and kd must be >= 0, got kp={kp}, kd={kd}')
        target = _finite('position', position) + _finite('position_offset', position_offset)
        tau0 = kp * target + kd * _finite('velocity', velocity) + _finite('torque', torque)
        self._mode = DriveMode.IMPEDANCE
        self._i0 = tau0 / p.torque_constant
        # q_out = rotor_angle / G, so d(tau)/d(rotor_angle) = kp / G, then / Kt for amperes.
        self._ki = kp / p.gear_ratio / p.torque_constant
        self._di = kd / p.gear_ratio / p.torque_constant

    # -- outputs -------------------------------------------------------------------------

    @property
    def angle(self) -> float:
        """Output-shaft angle, unwrapped [rad]."""
        return self.rotor_angle / self.params.gear_ratio

    @property
    def velocity(self) -> float:
        """Output-shaft angular velocity [rad/s]."""
        return self.rotor_velocity / self.params.gear_ratio

    @property
    def torque(self) -> float:
        """Electromagnetic torque at the output shaft [N·m]: Kt * I."""
        return self.params.torque_constant * self.current

    @property
    def electrical_power(self) -> float:
        """Power the motor takes from the supply now [W].

        The mechanical power ``torque * velocity`` plus the copper loss ``I**2 * R``;
        negative while it brakes regeneratively. (``back_emf_constant`` sets only the
        voltage limit: the model's phase-current and line-voltage constants differ, and
        ``I * Ke * w`` would count the mechanical power 1.5 times.)
        """
        current = self.current
        return (
            self.params.torque_constant * current * self.velocity
            + current * current * self._params.resistance
        )

    @property
    def rotor_rpm(self) -> float:
        """Rotor speed [rpm], as DJI ESCs report it."""
        return self.rotor_velocity * 60.0 / (2.0 * math.pi)

    @property
    def encoder_count(self) -> int:
        """Rotor angle as a DJI encoder reads it: 0 .. 8191, wrapping every rotor turn."""
        turns = self.rotor_angle / (2.0 * math.pi)
        return math.floor((turns - math.floor(turns)) * DJI_ENCODER_COUNTS) % DJI_ENCODER_COUNTS

    @property
    def kinetic_energy(self) -> float:
        """Kinetic energy of rotor and load [J]."""
        return 0.5 * self.params.inertia * self.rotor_velocity**2

    # -- dynamics ------------------------------------------------------------------------

    def reset(self, *, angle: float = 0.0, velocity: float = 0.0) -> None:
        """Put the output shaft at angle [rad] and velocity [rad/s], with zero current."""
        g = self.params.gear_ratio
        self.rotor_angle = _finite('angle', angle) * g
        self.rotor_velocity = _finite('velocity', velocity) * g
        self.current = 0.0

    def step(self, dt: float, *, stator_acceleration: float = 0.0) -> None:
        """Advance the state by dt [s].

        Args:
            dt: time step [s], > 0; 1e-3 is the design point.
            stator_acceleration: angular acceleration of the stator's mount about the motor
                axis [rad/s²] (e.g. a spinning chassis under a gimbal yaw motor); the load
                keeps its inertia in the world frame, so it lags relative to the stator.

        Raises:
            ValueError: dt not a positive finite number.
        """
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f'dt must be a positive finite number, got {dt}')
        if stator_acceleration != 0.0:
            stator_acceleration = _finite('stator_acceleration', stator_acceleration)
        p = self._params
        g = p.gear_ratio
        kt = self._kt
        inertia = self._inertia
        viscous = self._viscous
        coulomb = (p.coulomb_friction + max(0.0, self.brake_torque)) / g
        # Explicit over the step: the applied load and the fictitious torque of an
        # accelerating stator (the rotor-side angle is relative, the inertia is not).
        explicit = self.external_torque / g - inertia * g * stator_acceleration

        if self.locked:
            self.rotor_velocity = 0.0
            self.current = self._clamp_current(self._i0 - self._ki * self.rotor_angle, 0.0)
        else:
            # _solve, _law_current and _current_bounds inlined for the unsaturated step
            # (the usual one); the saturated one below keeps the helpers.
            i0, ki, di = self._i0, self._ki, self._di
            angle = self.rotor_angle
            denominator = inertia / dt + kt * ki * dt + kt * di + viscous
            free = (inertia * self.rotor_velocity / dt + kt * (i0 - ki * angle) + explicit) / (
                denominator
            )
            slip = coulomb / denominator
            if abs(free) <= slip:
                omega = 0.0
            else:
                omega = free - math.copysign(slip, free)
            current = i0 - ki * (angle + dt * omega) - di * omega
            back_emf = self._ke * omega
            i_max = p.max_current
            lo = max(-i_max, (-p.supply_voltage - back_emf) / p.resistance)
            hi = min(i_max, (p.supply_voltage - back_emf) / p.resistance)
            if current > hi or current < lo:
                terms = _StepTerms(dt, kt, inertia, viscous, coulomb, explicit)
                sign = 1.0 if current > hi else -1.0
                # Saturated: either the driver's current limit or the voltage limit holds.
                at_limit = (sign * p.max_current, 0.0, 0.0)
                omega = self._solve(terms, at_limit)
                v_lo, v_hi = self._voltage_bounds(omega)
                if (sign > 0 and p.max_current > v_hi) or (sign < 0 and -p.max_current < v_lo):
                    at_voltage = (
                        sign * p.supply_voltage / p.resistance, 0.0, self._ke / p.resistance
                    )
                    omega = self._solve(terms, at_voltage)
                    current = self._law_current(at_voltage, dt, omega)
                else:
                    current = sign * p.max_current
                current = self._clamp_current(current, omega)
            else:
                current = max(lo, min(hi, current))
            self.rotor_velocity = omega
            self.rotor_angle = angle + dt * omega
            self.current = current

        self._step_temperature(dt)

    def _law_current(self, law: tuple[float, float, float], dt: float, omega: float) -> float:
        i0, ki, di = law
        return i0 - ki * (self.rotor_angle + dt * omega) - di * omega

    def _solve(self, t: _StepTerms, law: tuple[float, float, float]) -> float:
        """Backward-Euler velocity under the current law ``I = i0 - ki*q' - di*w'``."""
        i0, ki, di = law
        dt = t.dt
        denominator = t.inertia / dt + t.kt * ki * dt + t.kt * di + t.viscous
        free = (
            t.inertia * self.rotor_velocity / dt + t.kt * (i0 - ki * self.rotor_angle) + t.explicit
        ) / denominator
        # Implicit Coulomb friction: it can remove at most coulomb/denominator of velocity in
        # one step; if that is enough, the rotor sticks (exactly zero, no chatter).
        slip = t.coulomb / denominator
        if abs(free) <= slip:
            return 0.0
        return free - math.copysign(slip, free)

    def _voltage_bounds(self, omega: float) -> tuple[float, float]:
        p = self.params
        back_emf = p.back_emf_constant / p.gear_ratio * omega
        return (-p.supply_voltage - back_emf) / p.resistance, (
            p.supply_voltage - back_emf
        ) / p.resistance

    def _current_bounds(self, omega: float) -> tuple[float, float]:
        v_lo, v_hi = self._voltage_bounds(omega)
        i_max = self.params.max_current
        return max(-i_max, v_lo), min(i_max, v_hi)

    def _clamp_current(self, current: float, omega: float) -> float:
        lo, hi = self._current_bounds(omega)
        return max(lo, min(hi, current))

    def _step_temperature(self, dt: float) -> None:
        if self.temperature_override is not None:
            self.temperature = float(self.temperature_override)
            return
        p = self._params
        # Implicit update of C*dT/dt = I²R - (T - T_amb)/R_th: stable for any dt.
        rate = dt / self._thermal_rc
        heat = dt * self.current**2 * p.resistance / p.thermal_capacitance
        self.temperature = (self.temperature + heat + rate * p.ambient_temperature) / (1.0 + rate)
