r"""Wheel kinematics of holonomic chassis (mecanum, omni) through one wheel Jacobian.

Why one module: one wheel Jacobian for mecanum and omni chassis, both directions, with the
layouts and their checks.

Frames and signs (REP 103): the base frame has x forward, y left, z up, its origin at the
point the chassis turns about. A twist (vx, vy, wz) is in m/s, m/s and rad/s, wz positive
counter-clockwise seen from above. Wheel speeds are angular speeds of the wheels [rad/s];
motor direction and gear ratio are applied by the actuator, not here.

The model. Wheel i is at (x_i, y_i) [m], radius r_i [m], and has

- a rolling direction beta_i [rad]: the direction, from base x counter-clockwise, in which
  its hub moves when it turns at positive speed without slipping (its driving direction);
- a roller angle gamma_i [rad]: the angle from the rolling direction to the axis of the
  roller touching the ground, counter-clockwise seen from above. Omni wheels have
  gamma = 0 (roller axes along the rim), mecanum wheels gamma = ±45°.

A roller turns freely about its axis, so it can slide across its axis but not along it.
Along the roller axis n_i = (cos(beta_i + gamma_i), sin(beta_i + gamma_i)) the velocity of
the wheel centre, v_i = (vx - wz * y_i, vy + wz * x_i), must therefore come from the wheel
turning, whose rim moves r_i * w_i * cos(gamma_i) along n_i:

.. math:: w_i = \frac{n_i \cdot v_i}{r_i \cos\gamma_i}
          = \frac{[\cos(\beta_i+\gamma_i),\ \sin(\beta_i+\gamma_i),\
            x_i \sin(\beta_i+\gamma_i) - y_i \cos(\beta_i+\gamma_i)]}{r_i \cos\gamma_i}
            \begin{bmatrix} v_x \\ v_y \\ \omega_z \end{bmatrix}

Stacking the rows gives the N x 3 Jacobian J: wheel speeds = J @ twist (inverse
kinematics). Forward kinematics is the least-squares solution, twist = pinv(J) @ wheel
speeds, exact when the wheels agree and a best fit when they slip.

Standard mecanum layout (:func:`mecanum_wheels`), wheels in the order front-left,
front-right, rear-left, rear-right, all rolling forward (beta = 0), roller angles
-45°, +45°, +45°, -45°, lx = wheelbase / 2, ly = track / 2:

- FL = (vx - vy - (lx + ly) wz) / r
- FR = (vx + vy + (lx + ly) wz) / r
- RL = (vx + vy - (lx + ly) wz) / r
- RR = (vx - vy + (lx + ly) wz) / r

These are the rollers one sees forming an X when looking down on the robot (the ground
rollers, seen through the robot, form an O), the usual RoboMaster and ros2_controllers
mecanum layout: driving left turns FL and RR backwards and FR and RL forwards.

Omni layout (:func:`omni_wheels`): wheel i at angle alpha_i [rad] from base x, distance R
from the centre, rolling direction alpha_i + 90° (positive speed turns the chassis
counter-clockwise), so w_i = (-sin(alpha_i) vx + cos(alpha_i) vy + R wz) / r.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from numbers import Real
from typing import Any, NamedTuple, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rm_base.errors import ConfigError, InputRejectedError

MECANUM_ROLLER_SIGNS = (-1, 1, 1, -1)
"""Roller angle signs of the standard mecanum layout, in the order FL, FR, RL, RR."""


class Twist2D(NamedTuple):
    """A planar velocity in some frame: vx, vy [m/s] and wz [rad/s]."""

    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0


def finite_config_value(owner: str, name: str, value: float) -> float:
    """Return value as a float; ConfigError naming owner.name if it is not finite."""
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
        raise ConfigError(f'{owner}.{name} must be a finite number, got {value!r}')
    return float(value)


@dataclass(frozen=True, slots=True)
class Wheel:
    """One wheel of a holonomic chassis; see the module docstring for the model.

    Attributes:
        x: Position along base x [m].
        y: Position along base y [m].
        radius: Wheel radius [m], > 0.
        rolling_direction: Direction the hub moves at positive wheel speed, from base x,
            counter-clockwise [rad].
        roller_angle: From the rolling direction to the axis of the ground roller,
            counter-clockwise [rad]: 0 for omni, ±pi/4 for mecanum wheels. Its cosine
            must not be 0 (a roller across the rim can't drive).
    """

    x: float
    y: float
    radius: float
    rolling_direction: float = 0.0
    roller_angle: float = 0.0

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ('x', 'y', 'radius', 'rolling_direction', 'roller_angle'):
            object.__setattr__(self, name, finite_config_value(owner, name, getattr(self, name)))
        if self.radius <= 0.0:
            raise ConfigError(f'{owner}.radius must be > 0 m, got {self.radius!r}')
        if abs(math.cos(self.roller_angle)) < 1e-6:
            raise ConfigError(
                f'{owner}.roller_angle {self.roller_angle!r} rad is across the rim; '
                'such a wheel cannot drive'
            )

    def jacobian_row(self) -> NDArray[np.float64]:
        """Return the row (d w / d vx, d w / d vy, d w / d wz) of this wheel [rad/m, rad/m, 1]."""
        axis = self.rolling_direction + self.roller_angle
        c, s = math.cos(axis), math.sin(axis)
        return np.array([c, s, self.x * s - self.y * c]) / (
            self.radius * math.cos(self.roller_angle)
        )


class WheelKinematics:
    """Inverse and forward kinematics of a set of wheels, through their Jacobian.

    The order of wheel speeds is the order of the wheels given at construction.
    """

    __slots__ = ('_jacobian', '_pinv_rows', '_pseudo_inverse', '_rows', '_wheels')

    def __init__(self, wheels: Sequence[Wheel]) -> None:
        """Build the Jacobian and its pseudo-inverse.

        Args:
            wheels: The wheels, in the order of the wheel speed vectors.

        Raises:
            ConfigError: If an entry is not a Wheel, or the wheels can't produce every
                twist (fewer than 3, or a Jacobian of rank < 3, e.g. all omni wheels
                rolling the same way).
        """
        wheels = tuple(wheels)
        for index, wheel in enumerate(wheels):
            if not isinstance(wheel, Wheel):
                raise ConfigError(f'wheel {index} must be a Wheel, got {wheel!r}')
        if len(wheels) < 3:
            raise ConfigError(f'a holonomic chassis needs >= 3 wheels, got {len(wheels)}')
        jacobian = np.array([wheel.jacobian_row() for wheel in wheels])
        if np.linalg.matrix_rank(jacobian) < 3:
            raise ConfigError(
                'these wheels cannot produce every (vx, vy, wz): check positions, rolling '
                'directions and roller angles'
            )
        jacobian.flags.writeable = False
        pseudo_inverse = np.linalg.pinv(jacobian)
        pseudo_inverse.flags.writeable = False
        self._wheels = wheels
        self._jacobian = jacobian
        self._pseudo_inverse = pseudo_inverse
        # Plain floats for the per-tick paths: numpy costs more than it saves on 4 x 3.
        self._rows = tuple(tuple(row) for row in jacobian.tolist())
        self._pinv_rows = tuple(tuple(row) for row in pseudo_inverse.tolist())

    @property
    def wheels(self) -> tuple[Wheel, ...]:
        """The wheels, in wheel speed order."""
        return self._wheels

    @property
    def jacobian(self) -> NDArray[np.float64]:
        """J (N x 3, read-only): wheel speeds [rad/s] = J @ (vx, vy, wz)."""
        return self._jacobian

    def inverse(self, twist: ArrayLike) -> NDArray[np.float64]:
        """Return the wheel speeds [rad/s] that drive the base at twist.

        Args:
            twist: (vx [m/s], vy [m/s], wz [rad/s]) in the base frame, e.g. a Twist2D.

        Raises:
            InputRejectedError: If twist is not 3 finite values.
        """
        vector = np.asarray(twist, dtype=float)
        if vector.shape != (3,) or not np.all(np.isfinite(vector)):
            raise InputRejectedError(f'twist must be 3 finite values (vx, vy, wz), got {twist!r}')
        wheel_speeds: NDArray[np.float64] = self._jacobian @ vector
        return wheel_speeds

    def forward(self, wheel_speeds: ArrayLike) -> Twist2D:
        """Return the base twist that best explains the wheel speeds (least squares).

        Args:
            wheel_speeds: One speed per wheel [rad/s], in wheel order.

        Raises:
            InputRejectedError: If the count is wrong or a speed is NaN or infinite.
        """
        speeds = _floats(wheel_speeds)
        if speeds is None or len(speeds) != len(self._wheels):
            raise InputRejectedError(
                f'expected {len(self._wheels)} finite wheel speeds, got {wheel_speeds!r}'
            )
        vx_row, vy_row, wz_row = self._pinv_rows
        return Twist2D(_dot(vx_row, speeds), _dot(vy_row, speeds), _dot(wz_row, speeds))

    def wheel_speeds(self, twist: Sequence[float]) -> tuple[float, ...]:
        """Return the wheel speeds [rad/s] that drive the base at twist, as plain floats.

        The same as :meth:`inverse`, for the per-tick paths that need no array.

        Args:
            twist: (vx [m/s], vy [m/s], wz [rad/s]) in the base frame, e.g. a Twist2D.

        Raises:
            InputRejectedError: If twist is not 3 finite values.
        """
        vector = _floats(twist)
        if vector is None or len(vector) != 3:
            raise InputRejectedError(f'twist must be 3 finite values (vx, vy, wz), got {twist!r}')
        vx, vy, wz = vector
        return tuple(a * vx + b * vy + c * wz for a, b, c in self._rows)


def mecanum_wheels(
    wheelbase: float,
    track: float,
    wheel_radius: float,
    roller_signs: Sequence[int] = MECANUM_ROLLER_SIGNS,
    roller_angle: float = math.pi / 4,
) -> tuple[Wheel, ...]:
    """Return four mecanum wheels on a rectangle centred on the base origin.

    Args:
        wheelbase: Distance between front and rear axles [m], > 0.
        track: Distance between left and right wheel centres [m], > 0.
        wheel_radius: Wheel radius [m], > 0.
        roller_signs: Sign (+1/-1) of each wheel's roller angle, in the order FL, FR, RL,
            RR; the default is the standard X layout (see the module docstring).
        roller_angle: Magnitude of the roller angle [rad], usually pi/4.

    Returns:
        The wheels in the order front-left, front-right, rear-left, rear-right, all rolling
        forward (rolling_direction 0).

    Raises:
        ConfigError: If a dimension is not finite and > 0 or a sign is not ±1.
    """
    for name, value in (('wheelbase', wheelbase), ('track', track)):
        if not finite_config_value('mecanum_wheels', name, value) > 0.0:
            raise ConfigError(f'mecanum_wheels.{name} must be > 0 m, got {value!r}')
    signs = tuple(roller_signs)
    if len(signs) != 4 or any(sign not in (1, -1) for sign in signs):
        raise ConfigError(f'roller_signs must be four of +1/-1 (FL, FR, RL, RR), got {signs!r}')
    lx, ly = 0.5 * wheelbase, 0.5 * track
    positions = ((lx, ly), (lx, -ly), (-lx, ly), (-lx, -ly))
    return tuple(
        Wheel(x, y, wheel_radius, rolling_direction=0.0, roller_angle=sign * roller_angle)
        for (x, y), sign in zip(positions, signs, strict=True)
    )


def omni_wheels(
    mounting_angles: Sequence[float], centre_distance: float, wheel_radius: float
) -> tuple[Wheel, ...]:
    """Return omni wheels on a circle, each rolling tangentially (counter-clockwise).

    Args:
        mounting_angles: Angle of each wheel's position from base x [rad], e.g.
            (pi/4, 3pi/4, 5pi/4, 7pi/4) for a 4-wheel chassis with wheels at the corners.
        centre_distance: Distance from the base origin to each wheel centre [m], > 0.
        wheel_radius: Wheel radius [m], > 0.

    Returns:
        The wheels in the order of mounting_angles.

    Raises:
        ConfigError: If a value is not finite, or centre_distance is not > 0.
    """
    if not finite_config_value('omni_wheels', 'centre_distance', centre_distance) > 0.0:
        raise ConfigError(f'omni_wheels.centre_distance must be > 0 m, got {centre_distance!r}')
    wheels = []
    for raw_angle in mounting_angles:
        angle = finite_config_value('omni_wheels', 'mounting_angles', raw_angle)
        wheels.append(
            Wheel(
                centre_distance * math.cos(angle),
                centre_distance * math.sin(angle),
                wheel_radius,
                rolling_direction=angle + 0.5 * math.pi,
            )
        )
    return tuple(wheels)


def desaturate(wheel_speeds: ArrayLike, max_speed: ArrayLike) -> NDArray[np.float64]:
    """Scale all wheel speeds by one factor so that none exceeds its maximum.

    Scaling every wheel alike scales the twist alike (kinematics are linear), so the
    chassis keeps its direction of motion and its ratio of turning to translating.

    Args:
        wheel_speeds: Wheel speeds [rad/s].
        max_speed: Largest allowed |speed| [rad/s], > 0: one value, or one per wheel.

    Returns:
        The scaled speeds (a new array); unchanged if all are within their maxima.

    Raises:
        InputRejectedError: If a speed is NaN or infinite, or max_speed is not > 0 or has
            the wrong shape.
    """
    speeds = np.array(wheel_speeds, dtype=float)
    if speeds.ndim != 1 or not np.all(np.isfinite(speeds)):
        raise InputRejectedError(f'wheel speeds must be finite, got {wheel_speeds!r}')
    maxima = np.asarray(max_speed, dtype=float)
    if maxima.shape not in ((), speeds.shape) or not np.all(maxima > 0.0):
        raise InputRejectedError(f'max_speed must be > 0, one or one per wheel, got {max_speed!r}')
    ratio = float(np.max(np.abs(speeds) / maxima)) if speeds.size else 0.0
    if ratio > 1.0:
        speeds /= ratio
    return speeds


def desaturate_speeds(
    wheel_speeds: Sequence[float], max_speed: float
) -> tuple[tuple[float, ...], float]:
    """Scale wheel speeds by one factor so that none exceeds max_speed; plain floats.

    :func:`desaturate` for one maximum, for the per-tick paths that need no array.

    Args:
        wheel_speeds: Wheel speeds [rad/s].
        max_speed: Largest allowed |speed| [rad/s], > 0.

    Returns:
        The scaled speeds and the factor k in (0, 1] they were scaled by (1: unchanged).

    Raises:
        InputRejectedError: If a speed is NaN or infinite, or max_speed is not > 0.
    """
    speeds = _floats(wheel_speeds)
    if speeds is None:
        raise InputRejectedError(f'wheel speeds must be finite, got {wheel_speeds!r}')
    if not max_speed > 0.0:
        raise InputRejectedError(f'max_speed must be > 0, got {max_speed!r}')
    peak = max(map(abs, speeds), default=0.0)
    ratio = peak / max_speed
    if not ratio > 1.0:
        return speeds, 1.0
    scaled = tuple(v / ratio for v in speeds)
    return scaled, max(map(abs, scaled)) / peak


def _floats(values: ArrayLike) -> tuple[float, ...] | None:
    """Return values as a tuple of floats, or None if one is not a finite number."""
    try:
        floats = tuple(map(float, cast(Iterable[Any], values)))  # TypeError if no sequence
    except (TypeError, ValueError):
        return None
    for value in floats:
        if not -math.inf < value < math.inf:
            return None
    return floats


def _dot(row: tuple[float, ...], values: tuple[float, ...]) -> float:
    total = 0.0
    for a, b in zip(row, values, strict=True):
        total += a * b
    return total


def _check_twist(twist: Sequence[float], yaw: float) -> tuple[float, float, float]:
    try:
        vx, vy, wz = (float(value) for value in twist)
        finite = all(map(math.isfinite, (vx, vy, wz, float(yaw))))
    except (TypeError, ValueError):
        finite = False
    if not finite:
        raise InputRejectedError(
            f'twist must be 3 finite values and yaw finite, got {twist!r}, {yaw!r}'
        )
    return vx, vy, wz


def body_to_world_twist(twist: Sequence[float], yaw: float) -> Twist2D:
    """Express a twist given in a body frame B in a frame W in which B heads yaw.

    The twist is rotated, not transformed: it is the same motion of the base, seen with
    other axes. E.g. a command in the gimbal frame becomes a chassis command with
    ``body_to_world_twist(command, yaw_joint)``, yaw_joint being the gimbal's heading
    relative to the chassis.

    Args:
        twist: (vx, vy, wz) in B [m/s, m/s, rad/s].
        yaw: Heading of B in W [rad], counter-clockwise.

    Returns:
        The twist in W: the linear part rotated by +yaw, wz unchanged.

    Raises:
        InputRejectedError: If a value is NaN or infinite.
    """
    vx, vy, wz = _check_twist(twist, yaw)
    c, s = math.cos(yaw), math.sin(yaw)
    return Twist2D(c * vx - s * vy, s * vx + c * vy, wz)


def world_to_body_twist(twist: Sequence[float], yaw: float) -> Twist2D:
    """Express a twist given in a frame W in a body frame B that heads yaw in W.

    The inverse of :func:`body_to_world_twist`, e.g. a world-frame command (GYRO mode)
    turned into the chassis frame with the chassis heading from odometry.

    Args:
        twist: (vx, vy, wz) in W [m/s, m/s, rad/s].
        yaw: Heading of B in W [rad], counter-clockwise.

    Returns:
        The twist in B: the linear part rotated by -yaw, wz unchanged.

    Raises:
        InputRejectedError: If a value is NaN or infinite.
    """
    vx, vy, wz = _check_twist(twist, yaw)
    c, s = math.cos(yaw), math.sin(yaw)
    return Twist2D(c * vx + s * vy, -s * vx + c * vy, wz)
