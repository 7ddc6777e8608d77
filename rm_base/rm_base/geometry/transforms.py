"""Rigid transforms in the plane (SE(2)) and in space (SE(3)) as homogeneous matrices.

Naming follows tf2: ``T_a_b`` (a transform "from b to a", the pose of frame b in frame
a) maps a point expressed in frame b to frame a, ``p_a = T_a_b.apply(p_b)``. Transforms
chain by ``@``: ``T_a_c = T_a_b @ T_b_c``; ``T_a_b.inverse()`` is ``T_b_a``. Units: m
and rad; frames per REP 103 (x forward, y left, z up). Quaternions are (x, y, z, w); see
:mod:`rm_base.geometry.rotations` for the roll/pitch/yaw convention.

Both classes are immutable: the matrix they expose is read-only.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any, Self, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rm_base.errors import InputRejectedError
from rm_base.geometry.rotations import (
    Quaternion,
    check_rotation_matrix,
    normalize_quaternion,
    quaternion_from_rotation_matrix,
    quaternion_from_rpy,
    rpy_from_quaternion,
)


def _check_homogeneous(matrix: ArrayLike, size: int) -> NDArray[np.float64]:
    homogeneous = np.array(matrix, dtype=float)  # a copy, so the caller can't mutate it
    if homogeneous.shape != (size, size) or not np.all(np.isfinite(homogeneous)):
        raise InputRejectedError(
            f'a homogeneous transform must be a finite {size}x{size} matrix, got {matrix!r}'
        )
    bottom = np.zeros(size)
    bottom[-1] = 1.0
    if not np.allclose(homogeneous[-1], bottom, rtol=0.0, atol=1e-9):
        raise InputRejectedError(f'the last row of a homogeneous transform must be {bottom}')
    homogeneous[-1] = bottom
    check_rotation_matrix(homogeneous[:-1, :-1])
    return homogeneous


def _finite_translation(value: ArrayLike) -> tuple[float, float, float]:
    """Return value as three finite floats (see SE3.from_translation_quaternion)."""
    try:
        x, y, z = map(float, cast(Iterable[Any], value))
    except (TypeError, ValueError):
        raise InputRejectedError(f'translation must be 3 finite values, got {value!r}') from None
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        raise InputRejectedError(f'translation must be 3 finite values, got {value!r}')
    return x, y, z


def _check_points(points: ArrayLike, size: int) -> NDArray[np.float64]:
    array = np.asarray(points, dtype=float)
    if array.ndim not in (1, 2) or array.shape[-1] != size:
        raise InputRejectedError(
            f'points must have shape ({size},) or (N, {size}), got {array.shape}'
        )
    if not np.all(np.isfinite(array)):
        raise InputRejectedError('points must be finite')
    return array


def _frozen(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    matrix.flags.writeable = False
    return matrix


class _RigidTransform:
    """What SE2 and SE3 share: a frozen homogeneous matrix of size DIM + 1."""

    __slots__ = ('_matrix',)
    DIM = 0  # 2 or 3

    def __init__(self, matrix: ArrayLike | None = None) -> None:
        """Create a transform from a homogeneous matrix (None: identity).

        Raises:
            InputRejectedError: If matrix is not a finite rigid transform of this size.
        """
        size = self.DIM + 1
        self._matrix = _frozen(
            np.eye(size) if matrix is None else _check_homogeneous(matrix, size)
        )

    @classmethod
    def _trusted(cls, matrix: NDArray[np.float64]) -> Self:
        transform = object.__new__(cls)
        transform._matrix = _frozen(matrix)
        return transform

    @classmethod
    def identity(cls) -> Self:
        """Return the identity transform."""
        return cls._trusted(np.eye(cls.DIM + 1))

    @property
    def matrix(self) -> NDArray[np.float64]:
        """The homogeneous matrix (read-only)."""
        return self._matrix

    @property
    def translation(self) -> NDArray[np.float64]:
        """The translation [m] (read-only)."""
        return self._matrix[: self.DIM, self.DIM]

    @property
    def rotation(self) -> NDArray[np.float64]:
        """The rotation matrix (read-only)."""
        return self._matrix[: self.DIM, : self.DIM]

    def compose(self, other: Self) -> Self:
        """Return ``self @ other``: other applied first, then self."""
        return self._trusted(self._matrix @ other._matrix)

    def __matmul__(self, other: Self) -> Self:
        if type(other) is not type(self):
            return NotImplemented
        return self.compose(other)

    def inverse(self) -> Self:
        """Return the inverse transform (T_b_a for T_a_b)."""
        n = self.DIM
        rotation_t = self._matrix[:n, :n].T
        inverse = np.eye(n + 1)
        inverse[:n, :n] = rotation_t
        inverse[:n, n] = -rotation_t @ self._matrix[:n, n]
        return self._trusted(inverse)

    def apply(self, points: ArrayLike) -> NDArray[np.float64]:
        """Transform one point (shape (DIM,)) or many (shape (N, DIM)) [m].

        Raises:
            InputRejectedError: If points has the wrong shape or a NaN/inf value.
        """
        n = self.DIM
        array = _check_points(points, n)
        return array @ self._matrix[:n, :n].T + self._matrix[:n, n]


class SE2(_RigidTransform):
    """A rigid transform in the plane: rotation by yaw, then translation by (x, y)."""

    __slots__ = ()
    DIM = 2

    @classmethod
    def from_xy_yaw(cls, x: float, y: float, yaw: float) -> SE2:
        """Return the transform of a pose at (x, y) [m] heading yaw [rad].

        Raises:
            InputRejectedError: If a value is NaN or infinite.
        """
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(yaw)):
            raise InputRejectedError(f'x, y, yaw must be finite, got {x!r}, {y!r}, {yaw!r}')
        c, s = math.cos(yaw), math.sin(yaw)
        return cls._trusted(np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]]))

    def to_xy_yaw(self) -> tuple[float, float, float]:
        """Return (x [m], y [m], yaw [rad] in [-pi, pi])."""
        return self.x, self.y, self.yaw

    @property
    def x(self) -> float:
        """Translation along x [m]."""
        return float(self._matrix[0, 2])

    @property
    def y(self) -> float:
        """Translation along y [m]."""
        return float(self._matrix[1, 2])

    @property
    def yaw(self) -> float:
        """Rotation [rad], counter-clockwise, in [-pi, pi]."""
        return math.atan2(self._matrix[1, 0], self._matrix[0, 0])

    def __repr__(self) -> str:
        return f'SE2.from_xy_yaw({self.x!r}, {self.y!r}, {self.yaw!r})'


class SE3(_RigidTransform):
    """A rigid transform in space: a rotation, then a translation."""

    __slots__ = ()
    DIM = 3

    @classmethod
    def from_translation_quaternion(cls, translation: ArrayLike, quaternion: ArrayLike) -> SE3:
        """Return the transform with translation (x, y, z) [m] and rotation (x, y, z, w).

        Raises:
            InputRejectedError: If translation is not 3 finite values or quaternion is not a
                (near-)unit quaternion.
        """
        # Built from plain floats in one array: senders of /tf call this per tick, where
        # numpy's per-call overhead is most of the cost.
        tx, ty, tz = _finite_translation(translation)
        x, y, z, w = normalize_quaternion(quaternion)
        return cls._trusted(np.array((
            (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w), tx),
            (2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w), ty),
            (2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y), tz),
            (0.0, 0.0, 0.0, 1.0),
        )))

    @classmethod
    def from_translation_rpy(
        cls, translation: ArrayLike, roll: float, pitch: float, yaw: float
    ) -> SE3:
        """Return the transform with translation (x, y, z) [m] and roll, pitch, yaw [rad].

        Raises:
            InputRejectedError: If a value is NaN or infinite.
        """
        return cls.from_translation_quaternion(translation, quaternion_from_rpy(roll, pitch, yaw))

    @classmethod
    def from_se2(cls, planar: SE2) -> SE3:
        """Return a planar transform as an SE(3) one (z = 0, rotation about z)."""
        matrix = np.eye(4)
        matrix[:2, :2] = planar.rotation
        matrix[:2, 3] = planar.translation
        return cls._trusted(matrix)

    def to_se2(self) -> SE2:
        """Return the planar part: (x, y) and the yaw of the rotation, dropping z, roll, pitch."""
        return SE2.from_xy_yaw(float(self._matrix[0, 3]), float(self._matrix[1, 3]), self.rpy[2])

    @property
    def quaternion(self) -> Quaternion:
        """The rotation as a unit quaternion (x, y, z, w) with w >= 0."""
        return quaternion_from_rotation_matrix(self._matrix[:3, :3])

    @property
    def rpy(self) -> tuple[float, float, float]:
        """The rotation as (roll, pitch, yaw) [rad]."""
        return rpy_from_quaternion(self.quaternion)

    def __repr__(self) -> str:
        translation = tuple(self.translation.tolist())
        return f'SE3.from_translation_quaternion({translation!r}, {tuple(self.quaternion)!r})'
