"""Aiming a gimbal at a point: world yaw and pitch, with optional bullet-drop compensation.

Frames (REP 103): the target is in the world (odom) frame; the chassis pose is
``T_odom_base``. The gimbal's yaw and pitch axes are assumed to cross at one point, the
*pitch axis centre*, fixed in the base frame (:class:`GimbalMount`), and the barrel to
lie on a line through it. The answer is the barrel direction in the world:

- ``yaw``: heading about world z, counter-clockwise from odom x [rad], in [-pi, pi];
- ``pitch``: REP 103 pitch about the gimbal's horizontal y axis [rad], **positive turns
  the barrel down**, measured from the horizontal (what an IMU-stabilised gimbal holds,
  whatever the chassis tilt).

The barrel then points along ``Rz(yaw) @ Ry(pitch) @ x = (cos p cos y, cos p sin y,
-sin p)``. Without a bullet speed it points straight at the target; with one, the pitch
is raised so the bullet drops onto it (:mod:`rm_base.geometry.ballistics`), and a barrel
length moves the launch point to the muzzle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry.ballistics import BallisticSolution, ProjectileModel, solve_ballistic
from rm_base.geometry.transforms import SE2, SE3

_MUZZLE_ITERATIONS = 20
_MUZZLE_TOLERANCE_RAD = 1e-10
_DRAG_FREE = ProjectileModel()


@dataclass(frozen=True, slots=True)
class GimbalMount:
    """Where the gimbal sits on the chassis.

    Attributes:
        pitch_axis_offset: (x, y, z) of the pitch axis centre (where the yaw and pitch
            axes cross) in the chassis base frame [m].
        barrel_length: Distance from the pitch axis centre to the muzzle along the
            barrel [m], >= 0; bullets start there.
    """

    pitch_axis_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    barrel_length: float = 0.0

    def __post_init__(self) -> None:
        owner = type(self).__name__
        try:
            offset = tuple(float(value) for value in self.pitch_axis_offset)
        except (TypeError, ValueError) as err:
            raise ConfigError(
                f'{owner}.pitch_axis_offset must be (x, y, z) in m, got {self.pitch_axis_offset!r}'
            ) from err
        if len(offset) != 3 or not all(math.isfinite(value) for value in offset):
            raise ConfigError(
                f'{owner}.pitch_axis_offset must be 3 finite values, got {self.pitch_axis_offset!r}'
            )
        object.__setattr__(self, 'pitch_axis_offset', offset)
        length = self.barrel_length
        if isinstance(length, bool) or not isinstance(length, Real) or not 0.0 <= length < math.inf:
            raise ConfigError(f'{owner}.barrel_length must be finite and >= 0 m, got {length!r}')
        object.__setattr__(self, 'barrel_length', float(length))


class AimSolution(NamedTuple):
    """Where to point the barrel.

    Attributes:
        yaw: World heading [rad], counter-clockwise from odom x, in [-pi, pi].
        pitch: REP 103 pitch from the horizontal [rad]; positive is barrel down.
        distance: Horizontal distance from the pitch axis centre to the target [m].
        time_of_flight_s: Bullet flight time from the muzzle [s], or None when aiming
            without ballistics.
    """

    yaw: float
    pitch: float
    distance: float
    time_of_flight_s: float | None


def pitch_axis_in_world(base_pose: SE3 | SE2, mount: GimbalMount) -> NDArray[np.float64]:
    """Return the pitch axis centre in the world frame [m].

    Args:
        base_pose: ``T_odom_base``, the chassis pose in the world; an SE2 is taken as
            level at z = 0.
        mount: Where the gimbal sits on the chassis.

    Raises:
        InputRejectedError: If base_pose is neither an SE3 nor an SE2.
    """
    pose = SE3.from_se2(base_pose) if isinstance(base_pose, SE2) else base_pose
    if not isinstance(pose, SE3):
        raise InputRejectedError(f'base_pose must be an SE3 or SE2, got {base_pose!r}')
    return pose.apply(mount.pitch_axis_offset)


def _vector3(name: str, value: ArrayLike) -> NDArray[np.float64]:
    vector = np.asarray(value, dtype=float)
    if vector.shape != (3,) or not np.all(np.isfinite(vector)):
        raise InputRejectedError(f'{name} must be 3 finite values (x, y, z) in m, got {value!r}')
    return vector


def aim_from_point(
    origin: ArrayLike,
    target: ArrayLike,
    *,
    bullet_speed: float | None = None,
    model: ProjectileModel = _DRAG_FREE,
    barrel_length: float = 0.0,
) -> AimSolution | None:
    """Return the world yaw and pitch that aim from origin (the pitch axis centre) at target.

    Args:
        origin: Pitch axis centre in the world [m].
        target: Target point in the world [m].
        bullet_speed: Muzzle speed [m/s], > 0, for bullet-drop compensation; None aims
            straight at the target.
        model: Drag and gravity (with a bullet speed).
        barrel_length: Pitch axis centre to muzzle [m], >= 0 (with a bullet speed): the
            shot starts at the muzzle, which moves with the pitch.

    Returns:
        The aim, or None if the target is out of range, or straight above or below the
        origin (the heading is undefined there).

    Raises:
        InputRejectedError: If origin or target is not 3 finite values, the bullet speed
            is not finite and > 0, or barrel_length is not finite and >= 0.
    """
    delta = _vector3('target', target) - _vector3('origin', origin)
    dx, dy, dz = delta.tolist()
    distance = math.hypot(dx, dy)
    if distance == 0.0:
        return None
    yaw = math.atan2(dy, dx)
    if bullet_speed is None:
        return AimSolution(yaw, -math.atan2(dz, distance), distance, None)
    if not (math.isfinite(bullet_speed) and bullet_speed > 0.0):
        raise InputRejectedError(f'bullet speed must be finite and > 0 m/s, got {bullet_speed!r}')
    if not 0.0 <= barrel_length < math.inf:
        raise InputRejectedError(f'barrel_length must be finite and >= 0 m, got {barrel_length!r}')
    solution = solve_ballistic(distance, dz, bullet_speed, model)
    if solution is not None and barrel_length > 0.0:
        solution = _from_muzzle(
            solution,
            distance=distance,
            height=dz,
            speed=bullet_speed,
            model=model,
            barrel_length=barrel_length,
        )
    if solution is None:
        return None
    return AimSolution(yaw, solution.pitch, distance, solution.time_of_flight_s)


def _from_muzzle(
    solution: BallisticSolution,
    *,
    distance: float,
    height: float,
    speed: float,
    model: ProjectileModel,
    barrel_length: float,
) -> BallisticSolution | None:
    """Refine a solution from the pitch axis centre into one from the muzzle.

    The muzzle sits barrel_length along the barrel, so where it is depends on the pitch
    being solved for: fixed-point iteration, contracting by about barrel_length /
    distance per step.
    """
    for _ in range(_MUZZLE_ITERATIONS):
        elevation = solution.elevation
        remaining = distance - barrel_length * math.cos(elevation)
        if remaining <= 0.0:
            return None  # the target is within the barrel's reach
        refined = solve_ballistic(
            remaining, height - barrel_length * math.sin(elevation), speed, model
        )
        if refined is None:
            return None
        if abs(refined.pitch - solution.pitch) <= _MUZZLE_TOLERANCE_RAD:
            return refined
        solution = refined
    return None


def aim_at(
    target: ArrayLike,
    base_pose: SE3 | SE2,
    mount: GimbalMount,
    *,
    bullet_speed: float | None = None,
    model: ProjectileModel = _DRAG_FREE,
) -> AimSolution | None:
    """Return the world yaw and pitch that aim a gimbal on a chassis at a world point.

    Args:
        target: Target point in the world (odom) frame [m].
        base_pose: ``T_odom_base``, the chassis pose (SE2: level at z = 0).
        mount: Pitch axis centre on the chassis and barrel length.
        bullet_speed: Muzzle speed [m/s] for bullet-drop compensation; None aims
            straight at the target.
        model: Drag and gravity (with a bullet speed).

    Returns:
        As :func:`aim_from_point`.

    Raises:
        InputRejectedError: As :func:`aim_from_point`, or if base_pose is not an SE3/SE2.
    """
    return aim_from_point(
        pitch_axis_in_world(base_pose, mount),
        target,
        bullet_speed=bullet_speed,
        model=model,
        barrel_length=mount.barrel_length,
    )
