r"""Swerve (steered-wheel) chassis kinematics: module states from a twist and back.

Frames and signs as :mod:`rm_base.geometry.kinematics` (REP 103, base origin at the point
the chassis turns about). Module i sits at (x_i, y_i) [m] with a wheel of radius r_i [m]
that a steering joint points at angle theta_i [rad] from base x, counter-clockwise; the
wheel's speed w_i [rad/s] is positive when its hub moves along theta_i. A steered wheel
has no rollers: it neither slips along nor across its direction.

Inverse. The hub's velocity is v_i = (vx - wz y_i, vy + wz x_i); the module points along
it and turns at |v_i| / r_i. Turning a module by more than 90° is never needed: pointing
the opposite way and driving backwards gives the same hub velocity, so
:func:`nearest_module_state` keeps every module within 90° of where it points now, and
leaves a module where it is when it should not move at all. While a module is still
turning, its speed is scaled by the cosine of its angle error, so a wheel pointing off
its direction does not push the chassis sideways (at 90° off it stands).

Forward (odometry, the simulator). Each module gives two equations on the twist: along
its direction the hub moves at r_i w_i, across it not at all::

    [ cos t,  sin t,  x sin t - y cos t] . twist = r w
    [-sin t,  cos t,  x cos t + y sin t] . twist = 0

and the twist is the least-squares solution of the 2N equations: exact when the modules
agree, a best fit when they fight each other.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry.angles import wrap_to_pi
from rm_base.geometry.kinematics import Twist2D, finite_config_value

_HALF_PI = 0.5 * math.pi


@dataclass(frozen=True, slots=True)
class SwerveModule:
    """One steered wheel.

    Attributes:
        x: position along base x [m].
        y: position along base y [m].
        radius: wheel radius [m], > 0.
    """

    x: float
    y: float
    radius: float

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ('x', 'y', 'radius'):
            object.__setattr__(self, name, finite_config_value(owner, name, getattr(self, name)))
        if self.radius <= 0.0:
            raise ConfigError(f'{owner}.radius must be > 0 m, got {self.radius!r}')


class ModuleState(NamedTuple):
    """Where a module points [rad] and how fast its wheel turns [rad/s]."""

    angle: float
    speed: float


def nearest_module_state(direction: float, speed: float, current: float) -> ModuleState:
    """The module state within 90° of current that drives the hub along direction at speed.

    Args:
        direction: the hub's velocity direction [rad] (any value).
        speed: the wheel speed along direction [rad/s], >= 0 (0: do not move).
        current: where the module points now [rad], unwrapped as the steering joint
            counts it; the result is current plus a turn in [-pi/2, pi/2].

    Returns:
        The angle (near current, in the same counting) and the signed wheel speed; a speed
        of 0 keeps the angle.
    """
    if speed == 0.0:
        return ModuleState(current, 0.0)
    turn = wrap_to_pi(direction - current)
    if turn > _HALF_PI:
        turn -= math.pi
        speed = -speed
    elif turn < -_HALF_PI:
        turn += math.pi
        speed = -speed
    return ModuleState(current + turn, speed)


class SwerveKinematics:
    """Module states for a twist, and the twist of measured module states."""

    def __init__(self, modules: Sequence[SwerveModule]) -> None:
        """Raises ConfigError: fewer than two modules, or two at one place."""
        modules = tuple(modules)
        if len(modules) < 2 or not all(isinstance(m, SwerveModule) for m in modules):
            raise ConfigError(f'a swerve chassis needs at least two SwerveModule, got {modules!r}')
        places = {(m.x, m.y) for m in modules}
        if len(places) < len(modules):
            raise ConfigError('two swerve modules at one place: the twist is not determined')
        self._modules = modules

    @property
    def modules(self) -> tuple[SwerveModule, ...]:
        """The modules, in order."""
        return self._modules

    def module_states(
        self,
        twist: Sequence[float],
        current: Sequence[float],
        *,
        measured: Sequence[float] | None = None,
    ) -> tuple[ModuleState, ...]:
        """Inverse kinematics with each module kept within 90° of where it points.

        Args:
            twist: (vx [m/s], vy [m/s], wz [rad/s]).
            current: the angles the modules are steered to now [rad] (their targets).
            measured: the angles they are at [rad]; when given, each speed is scaled by
                the cosine of the module's error to its new angle (0 beyond 90°).

        Raises:
            InputRejectedError: a value is NaN or infinite, or a length is wrong.
        """
        vx, vy, wz = _finite('twist', twist, 3)
        current = _finite('current angles', current, len(self._modules))
        if measured is not None:
            measured = _finite('measured angles', measured, len(self._modules))
        states = []
        for i, m in enumerate(self._modules):
            hx, hy = vx - wz * m.y, vy + wz * m.x
            speed = math.hypot(hx, hy) / m.radius
            state = nearest_module_state(math.atan2(hy, hx), speed, current[i])
            if measured is not None and state.speed != 0.0:
                scale = max(0.0, math.cos(state.angle - measured[i]))
                state = ModuleState(state.angle, state.speed * scale)
            states.append(state)
        return tuple(states)

    def forward(self, angles: Sequence[float], speeds: Sequence[float]) -> Twist2D:
        """The chassis twist that best explains the modules' angles [rad] and speeds [rad/s].

        Raises:
            InputRejectedError: a value is NaN or infinite, or a length is wrong.
        """
        n = len(self._modules)
        angles = _finite('angles', angles, n)
        speeds = _finite('speeds', speeds, n)
        rows = np.empty((2 * n, 3))
        rhs = np.zeros(2 * n)
        for i, (m, t, w) in enumerate(zip(self._modules, angles, speeds, strict=True)):
            c, s = math.cos(t), math.sin(t)
            rows[2 * i] = (c, s, m.x * s - m.y * c)
            rows[2 * i + 1] = (-s, c, m.x * c + m.y * s)
            rhs[2 * i] = m.radius * w
        vx, vy, wz = np.linalg.lstsq(rows, rhs, rcond=None)[0].tolist()
        return Twist2D(vx, vy, wz)


def square_modules(wheelbase: float, track: float, radius: float) -> tuple[SwerveModule, ...]:
    """Four modules at the corners, in the order front-left, front-right, rear-left, rear-right."""
    lx, ly = 0.5 * wheelbase, 0.5 * track
    return tuple(
        SwerveModule(x, y, radius) for x, y in ((lx, ly), (lx, -ly), (-lx, ly), (-lx, -ly))
    )


def _finite(name: str, values: Sequence[float], length: int) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError) as err:
        raise InputRejectedError(f'{name} must be {length} numbers, got {values!r}') from err
    if len(out) != length or not all(map(math.isfinite, out)):
        raise InputRejectedError(f'{name} must be {length} finite numbers, got {values!r}')
    return out
