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

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rm_base.errors import InputRejectedError
from rm_base.geometry.rotations import (
    Quaternion,
    check_rotation_matrix,
    quaternion_from_rotation_matrix,
    rotation_matrix_from_quaternion,
    rotation_matrix_from_rpy,
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


def _check_vector(name: str, value: ArrayLike, size: int) -> NDArray[np.float64]:
    vector = np.asarray(value, dtype=float)
    if vector.shape != (size,) or not np.all(np.isfinite(vector)):
        raise InputRejectedError(f'{name} must be {size} finite values, got {value!r}')
    return vector


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


class SE2:
    """A rigid transform in the plane: rotation by yaw, then translation by (x, y)."""

    __slots__ = ('_matrix',)

    def __init__(self, matrix: ArrayLike | None = None) -> None:
        """Create a transform from a 3x3 homogeneous matrix (None: identity).

        Raises:
            InputRejectedError: If matrix is not a finite 3x3 rigid transform.
        """
        self._matrix = _frozen(np.eye(3) if matrix is None else _check_homogeneous(matrix, 3))

    @classmethod
    def _trusted(cls, matrix: NDArray[np.float64]) -> SE2:
        transform = object.__new__(cls)
        transform._matrix = _frozen(matrix)
        return transform

    @classmethod
    def identity(cls) -> SE2:
        """Return the identity transform."""
        return cls._trusted(np.eye(3))

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
    def matrix(self) -> NDArray[np.float64]:
        """The 3x3 homogeneous matrix (read-only)."""
        return self._matrix

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

    @property
    def translation(self) -> NDArray[np.float64]:
        """(x, y) [m] (read-only)."""
        return self._matrix[:2, 2]

    @property
    def rotation(self) -> NDArray[np.float64]:
        """The 2x2 rotation matrix (read-only)."""
        return self._matrix[:2, :2]

    def compose(self, other: SE2) -> SE2:
        """Return ``self @ other``: other applied first, then self."""
        return self._trusted(self._matrix @ other._matrix)

    def __matmul__(self, other: SE2) -> SE2:
        if not isinstance(other, SE2):
            return NotImplemented
        return self.compose(other)

    def inverse(self) -> SE2:
        """Return the inverse transform (T_b_a for T_a_b)."""
        rotation_t = self._matrix[:2, :2].T
        inverse = np.eye(3)
        inverse[:2, :2] = rotation_t
        inverse[:2, 2] = -rotation_t @ self._matrix[:2, 2]
        return self._trusted(inverse)

    def apply(self, points: ArrayLike) -> NDArray[np.float64]:
        """Transform one point (shape (2,)) or many (shape (N, 2)) [m].

        Raises:
            InputRejectedError: If points has the wrong shape or a NaN/inf value.
        """
        array = _check_points(points, 2)
        return array @ self._matrix[:2, :2].T + self._matrix[:2, 2]

    def __repr__(self) -> str:
        return f'SE2.from_xy_yaw({self.x!r}, {self.y!r}, {self.yaw!r})'


class SE3:
    """A rigid transform in space: a rotation, then a translation."""

    __slots__ = ('_matrix',)

    def __init__(self, matrix: ArrayLike | None = None) -> None:
        """Create a transform from a 4x4 homogeneous matrix (None: identity).

        Raises:
            InputRejectedError: If matrix is not a finite 4x4 rigid transform.
        """
        self._matrix = _frozen(np.eye(4) if matrix is None else _check_homogeneous(matrix, 4))

    @classmethod
    def _trusted(cls, matrix: NDArray[np.float64]) -> SE3:
        transform = object.__new__(cls)
        transform._matrix = _frozen(matrix)
        return transform

    @classmethod
    def _from_parts(cls, translation: ArrayLike, rotation: NDArray[np.float64]) -> SE3:
        matrix = np.eye(4)
        matrix[:3, :3] = rotation
        matrix[:3, 3] = _check_vector('translation', translation, 3)
        return cls._trusted(matrix)

    @classmethod
    def identity(cls) -> SE3:
        """Return the identity transform."""
        return cls._trusted(np.eye(4))

    @classmethod
    def from_translation_quaternion(cls, translation: ArrayLike, quaternion: ArrayLike) -> SE3:
        """Return the transform with translation (x, y, z) [m] and rotation (x, y, z, w).

        Raises:
            InputRejectedError: If translation is not 3 finite values or quaternion is not a
                (near-)unit quaternion.
        """
        return cls._from_parts(translation, rotation_matrix_from_quaternion(quaternion))

    @classmethod
    def from_translation_rpy(
        cls, translation: ArrayLike, roll: float, pitch: float, yaw: float
    ) -> SE3:
        """Return the transform with translation (x, y, z) [m] and roll, pitch, yaw [rad].

        Raises:
            InputRejectedError: If a value is NaN or infinite.
        """
        return cls._from_parts(translation, rotation_matrix_from_rpy(roll, pitch, yaw))

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
    def matrix(self) -> NDArray[np.float64]:
        """The 4x4 homogeneous matrix (read-only)."""
        return self._matrix

    @property
    def translation(self) -> NDArray[np.float64]:
        """(x, y, z) [m] (read-only)."""
        return self._matrix[:3, 3]

    @property
    def rotation(self) -> NDArray[np.float64]:
        """The 3x3 rotation matrix (read-only)."""
        return self._matrix[:3, :3]

    @property
    def quaternion(self) -> Quaternion:
        """The rotation as a unit quaternion (x, y, z, w) with w >= 0."""
        return quaternion_from_rotation_matrix(self._matrix[:3, :3])

    @property
    def rpy(self) -> tuple[float, float, float]:
        """The rotation as (roll, pitch, yaw) [rad]."""
        return rpy_from_quaternion(self.quaternion)

    def compose(self, other: SE3) -> SE3:
        """Return ``self @ other``: other applied first, then self."""
        return self._trusted(self._matrix @ other._matrix)

    def __matmul__(self, other: SE3) -> SE3:
        if not isinstance(other, SE3):
            return NotImplemented
        return self.compose(other)

    def inverse(self) -> SE3:
        """Return the inverse transform (T_b_a for T_a_b)."""
        rotation_t = self._matrix[:3, :3].T
        inverse = np.eye(4)
        inverse[:3, :3] = rotation_t
        inverse[:3, 3] = -rotation_t @ self._matrix[:3, 3]
        return self._trusted(inverse)

    def apply(self, points: ArrayLike) -> NDArray[np.float64]:
        """Transform one point (shape (3,)) or many (shape (N, 3)) [m].

        Raises:
            InputRejectedError: If points has the wrong shape or a NaN/inf value.
        """
        array = _check_points(points, 3)
        return array @ self._matrix[:3, :3].T + self._matrix[:3, 3]

    def __repr__(self) -> str:
        translation = tuple(self.translation.tolist())
        return f'SE3.from_translation_quaternion({translation!r}, {tuple(self.quaternion)!r})'
