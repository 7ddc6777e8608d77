"""Quaternions, roll/pitch/yaw and rotation matrices (REP 103: x forward, y left, z up).

Conventions:

- Quaternions are :class:`Quaternion` named tuples in ROS order **(x, y, z, w)**, as in
  ``geometry_msgs/Quaternion`` and tf2 (not the (w, x, y, z) order of many maths texts).
  They are Hamilton quaternions; a unit quaternion q rotates a vector v as q v q*.
- Roll, pitch, yaw are the angles of tf2's ``setRPY``: rotate about the fixed x axis by
  roll, then the fixed y axis by pitch, then the fixed z axis by yaw, i.e.
  ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``. Positive angles are counter-clockwise looking
  down the axis (right-hand rule): positive yaw turns left, positive pitch noses down.
- Angles in rad; returned roll and yaw in [-pi, pi], pitch in [-pi/2, pi/2].

Quaternions from outside are checked like tf2 does: one whose squared norm is within
0.01 of 1 is normalised, anything else (zero, NaN, far from unit) is rejected.
"""

import math
from collections.abc import Iterable
from typing import Any, NamedTuple, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rm_base.errors import InputRejectedError

_NORM_SQUARED_TOLERANCE = 0.01  # tf2's QUATERNION_NORMALIZATION_TOLERANCE
_ORTHONORMAL_TOLERANCE = 1e-6


class Quaternion(NamedTuple):
    """A rotation as a unit quaternion, in ROS order (x, y, z, w); default identity."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    w: float = 1.0


def normalize_quaternion(q: ArrayLike) -> Quaternion:
    """Return q, given in (x, y, z, w) order, as a unit Quaternion.

    Raises:
        InputRejectedError: If q has not 4 finite entries or its squared norm is not
            within 0.01 of 1 (tf2's tolerance).
    """
    # Plain floats: called per IMU sample and per tick, where numpy's overhead dominates.
    try:
        x, y, z, w = map(float, cast(Iterable[Any], q))  # TypeError if q is no sequence
    except (TypeError, ValueError):
        finite = False
    else:
        finite = math.isfinite(x) and math.isfinite(y) and math.isfinite(z) and math.isfinite(w)
    if not finite:
        raise InputRejectedError(f'a quaternion needs 4 finite values (x, y, z, w), got {q!r}')
    norm_squared = x * x + y * y + z * z + w * w
    if abs(norm_squared - 1.0) > _NORM_SQUARED_TOLERANCE:
        raise InputRejectedError(f'quaternion {q!r} is not a unit quaternion')
    norm = math.sqrt(norm_squared)
    return Quaternion(x / norm, y / norm, z / norm, w / norm)


def _require_finite_angles(**angles: float) -> None:
    for name, angle in angles.items():
        if not math.isfinite(angle):
            raise InputRejectedError(f'{name} must be a finite angle in rad, got {angle!r}')


def quaternion_from_rpy(roll: float, pitch: float, yaw: float) -> Quaternion:
    """Return the quaternion of ``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (angles in rad).

    Raises:
        InputRejectedError: If an angle is NaN or infinite.
    """
    _require_finite_angles(roll=roll, pitch=pitch, yaw=yaw)
    cr, sr = math.cos(0.5 * roll), math.sin(0.5 * roll)
    cp, sp = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    cy, sy = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return Quaternion(
        x=sr * cp * cy - cr * sp * sy,
        y=cr * sp * cy + sr * cp * sy,
        z=cr * cp * sy - sr * sp * cy,
        w=cr * cp * cy + sr * sp * sy,
    )


def quaternion_from_yaw(yaw: float) -> Quaternion:
    """Return the quaternion of a rotation by yaw [rad] about z.

    Raises:
        InputRejectedError: If yaw is NaN or infinite.
    """
    _require_finite_angles(yaw=yaw)
    return Quaternion(0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


def rpy_from_quaternion(q: ArrayLike) -> tuple[float, float, float]:
    """Return (roll, pitch, yaw) [rad] of q, given in (x, y, z, w) order.

    At pitch = ±pi/2 (gimbal lock) only roll - yaw (or roll + yaw) is defined; the split
    returned there is arbitrary but the angles still give back the same rotation.

    Raises:
        InputRejectedError: If q is not a (near-)unit quaternion.
    """
    x, y, z, w = normalize_quaternion(q)
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


def yaw_from_quaternion(q: ArrayLike) -> float:
    """Return the yaw [rad] of q (the yaw of its roll/pitch/yaw), in [-pi, pi].

    Raises:
        InputRejectedError: If q is not a (near-)unit quaternion.
    """
    x, y, z, w = normalize_quaternion(q)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quaternion_multiply(a: ArrayLike, b: ArrayLike) -> Quaternion:
    """Return the Hamilton product a * b (rotate by b, then by a), both in (x, y, z, w).

    Raises:
        InputRejectedError: If a or b is not a (near-)unit quaternion.
    """
    ax, ay, az, aw = normalize_quaternion(a)
    bx, by, bz, bw = normalize_quaternion(b)
    return Quaternion(
        x=aw * bx + ax * bw + ay * bz - az * by,
        y=aw * by - ax * bz + ay * bw + az * bx,
        z=aw * bz + ax * by - ay * bx + az * bw,
        w=aw * bw - ax * bx - ay * by - az * bz,
    )


def quaternion_inverse(q: ArrayLike) -> Quaternion:
    """Return the inverse rotation of q (its conjugate, as q is unit).

    Raises:
        InputRejectedError: If q is not a (near-)unit quaternion.
    """
    x, y, z, w = normalize_quaternion(q)
    return Quaternion(-x, -y, -z, w)


def rotation_matrix_from_quaternion(q: ArrayLike) -> NDArray[np.float64]:
    """Return the 3x3 rotation matrix of q, given in (x, y, z, w) order.

    Raises:
        InputRejectedError: If q is not a (near-)unit quaternion.
    """
    x, y, z, w = normalize_quaternion(q)
    return np.array(
        [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ]
    )


def rotation_matrix_from_rpy(roll: float, pitch: float, yaw: float) -> NDArray[np.float64]:
    """Return ``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (angles in rad).

    Raises:
        InputRejectedError: If an angle is NaN or infinite.
    """
    return rotation_matrix_from_quaternion(quaternion_from_rpy(roll, pitch, yaw))


def check_rotation_matrix(matrix: ArrayLike) -> NDArray[np.float64]:
    """Return matrix as a float array if it is a 3x3 or 2x2 rotation matrix.

    Raises:
        InputRejectedError: If it is not square 2x2/3x3, not finite, not orthonormal
            (within 1e-6) or a reflection.
    """
    rotation = np.asarray(matrix, dtype=float)
    if rotation.shape not in ((2, 2), (3, 3)) or not np.all(np.isfinite(rotation)):
        raise InputRejectedError(f'a rotation matrix must be finite 2x2 or 3x3, got {matrix!r}')
    identity = np.eye(rotation.shape[0])
    if not np.allclose(rotation.T @ rotation, identity, rtol=0.0, atol=_ORTHONORMAL_TOLERANCE):
        raise InputRejectedError('matrix is not orthonormal, so not a rotation')
    if np.linalg.det(rotation) < 0.0:
        raise InputRejectedError('matrix is a reflection (det = -1), not a rotation')
    return rotation


def quaternion_from_rotation_matrix(matrix: ArrayLike) -> Quaternion:
    """Return the unit quaternion (with w >= 0) of a 3x3 rotation matrix.

    Raises:
        InputRejectedError: If matrix is not a 3x3 rotation matrix.
    """
    m = check_rotation_matrix(matrix)
    if m.shape != (3, 3):
        raise InputRejectedError('a quaternion needs a 3x3 rotation matrix')
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = m.tolist()
    trace = m00 + m11 + m22
    # Shepperd's method: divide by the largest of 4w², 4x², 4y², 4z² for accuracy.
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)  # 4w
        x, y, z, w = (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s
    elif m00 > m11 and m00 > m22:
        s = 2.0 * math.sqrt(1.0 + m00 - m11 - m22)  # 4x
        x, y, z, w = 0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s
    elif m11 > m22:
        s = 2.0 * math.sqrt(1.0 + m11 - m00 - m22)  # 4y
        x, y, z, w = (m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s
    else:
        s = 2.0 * math.sqrt(1.0 + m22 - m00 - m11)  # 4z
        x, y, z, w = (m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s
    if w < 0.0:
        x, y, z, w = -x, -y, -z, -w
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    return Quaternion(x / norm, y / norm, z / norm, w / norm)
