"""Where a spinning robot's armour will be, and which one to aim at (pure maths).

A tracked robot (rm_auto_aim's Target, docs/AUTO_AIM.md) is a rotation centre c moving at
v, spinning at v_yaw, with armours_num armours around it: armour i's yaw is
psi_i = yaw + 2 pi i / N, its position c - r_i (cos psi_i, sin psi_i) at height z_i, where
for N = 4 the radii alternate r1, r2 and the heights z, z + dz (the tracker's own model).
Predicted t seconds ahead: c + v t and yaw + v_yaw t.

The armour to aim at is the one facing the shooter: its yaw closest to alpha, the bearing
from the shooter to the centre, with the angles wrapped (a solver that compares them
unwrapped picks the wrong plate near +-pi), shifted by ``lead`` against the spin, so that
the plate coming into view is preferred to the one leaving it. A spin faster than the
gimbal can follow aims at the centre instead (a plate passes through it every
2 pi / (N |v_yaw|) s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rm_base.errors import InputRejectedError
from rm_base.geometry.angles import wrap_to_pi


@dataclass(frozen=True)
class ArmorTarget:
    """A tracked robot, in one world frame (SI units).

    Attributes:
        center: the rotation centre (x, y) [m].
        z: the tracked armour's height [m].
        velocity: the centre's (vx, vy, vz) [m/s].
        yaw: the tracked armour's yaw [rad]; v_yaw its spin [rad/s].
        radius_1, radius_2: the tracked pair's and the other pair's radii [m].
        dz: the other pair's height above the tracked one [m].
        armors_num: 2, 3 or 4.
    """

    center: tuple[float, float]
    z: float
    velocity: tuple[float, float, float]
    yaw: float
    v_yaw: float
    radius_1: float
    radius_2: float
    dz: float
    armors_num: int

    def __post_init__(self) -> None:
        numbers = (*self.center, self.z, *self.velocity, self.yaw, self.v_yaw, self.radius_1,
                   self.radius_2, self.dz)
        if not all(math.isfinite(n) for n in numbers):
            raise InputRejectedError(f'target with a NaN or infinite value: {numbers}')
        if self.armors_num not in (2, 3, 4):
            raise InputRejectedError(f'armors_num must be 2, 3 or 4, got {self.armors_num}')
        if not (self.radius_1 > 0.0 and self.radius_2 >= 0.0):
            raise InputRejectedError(f'radii {self.radius_1}, {self.radius_2}: r1 > 0, r2 >= 0')


@dataclass(frozen=True)
class Armor:
    """One armour's predicted pose: position (x, y, z) [m] and yaw [rad, wrapped]."""

    index: int
    position: tuple[float, float, float]
    yaw: float


def armors(target: ArmorTarget, t_s: float) -> list[Armor]:
    """Every armour of target, t_s seconds ahead."""
    vx, vy, vz = target.velocity
    cx, cy = target.center[0] + vx * t_s, target.center[1] + vy * t_s
    base_yaw = target.yaw + target.v_yaw * t_s
    n = target.armors_num
    out = []
    for i in range(n):
        psi = base_yaw + 2.0 * math.pi * i / n
        odd = n == 4 and i % 2 == 1
        r = target.radius_2 if odd else target.radius_1
        z = target.z + vz * t_s + (target.dz if odd else 0.0)
        out.append(Armor(i, (cx - r * math.cos(psi), cy - r * math.sin(psi), z),
                         wrap_to_pi(psi)))
    return out


def facing_armor(target: ArmorTarget, t_s: float, shooter: tuple[float, float],
                 lead: float) -> Armor:
    """The armour facing shooter t_s seconds ahead (see the module docstring).

    lead [rad]: how far the choice leans toward the plate coming into view.
    """
    vx, vy, _ = target.velocity
    cx, cy = target.center[0] + vx * t_s, target.center[1] + vy * t_s
    alpha = math.atan2(cy - shooter[1], cx - shooter[0])
    bias = math.copysign(lead, target.v_yaw) if target.v_yaw else 0.0
    return min(armors(target, t_s), key=lambda a: abs(wrap_to_pi(a.yaw - alpha + bias)))


def center_point(target: ArmorTarget, t_s: float) -> tuple[float, float, float]:
    """The rotation centre t_s seconds ahead, at the armours' mean height."""
    vx, vy, vz = target.velocity
    z = target.z + vz * t_s + (target.dz / 2 if target.armors_num == 4 else 0.0)
    return (target.center[0] + vx * t_s, target.center[1] + vy * t_s, z)
