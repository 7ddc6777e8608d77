"""A spinning robot to shoot at: armour plates around a centre, and the hits on them.

The simulated enemy moves as rm_auto_aim's tracker models one (rm_base.geometry.
armor_target): a centre at a constant velocity, spinning at ``v_yaw``, with ``armors``
plates (``width`` x ``height``) at ``radius`` (and ``radius_2``, ``dz`` for the second
pair of four). Each projectile the simulated launcher fires leaves the muzzle
(``barrel_length`` along the barrel from the pitch axis, ``pivot_height`` up) along the
gimbal's world yaw and pitch at its speed, without drag; the first plate whose front face
its path crosses, within the plate, is hit. Plates are judged at the moment the
projectile reaches them, so the spin during the flight counts. A plate seen edge-on (its
face turned more than ``max_incidence`` from the path) deflects the projectile: no hit.
The robot's body hides nothing else.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping
from typing import Any, NamedTuple

from rm_base.config.schema import Schema, integer, number
from rm_base.geometry.armor_target import Armor, ArmorTarget, armors
from rm_base.sim_devices.errors import SimConfigError

_NS_PER_S = 1_000_000_000
GRAVITY = 9.81

#: The world's ``target``.
TARGET_SCHEMA = Schema((
    number('x', 4.0, unit='m', description='the centre at the start, x in the world frame'),
    number('y', 0.0, unit='m', description='the centre at the start, y'),
    number('z', 0.3, unit='m', description="the first pair of plates' height"),
    number('vx', 0.0, unit='m/s', description="the centre's velocity, x"),
    number('vy', 0.0, unit='m/s', description="the centre's velocity, y"),
    number('yaw', 0.0, unit='rad', description="plate 0's yaw at the start"),
    number('v_yaw', 2.0, unit='rad/s', description='spin'),
    number('radius', 0.25, unit='m', gt=0.0, description='plates 0 and 2 from the centre'),
    number('radius_2', 0.25, unit='m', gt=0.0, description='plates 1 and 3 (of four)'),
    number('dz', 0.0, unit='m', description='plates 1 and 3 above plates 0 and 2 (of four)'),
    integer('armors', 4, ge=2, le=4, description='plates around the centre: 2, 3 or 4'),
    number('width', 0.135, unit='m', gt=0.0, description='plate width (small armour)'),
    number('height', 0.125, unit='m', gt=0.0, description='plate height'),
    number('max_incidence', 1.2, unit='rad', gt=0.0, le=math.pi / 2,
           description='a plate turned further from the path deflects the projectile'),
    number('pivot_height', 0.35, unit='m',
           description="the gimbal's pitch axis above the ground"),
    number('barrel_length', 0.15, unit='m', ge=0.0,
           description='pitch axis to muzzle (projectiles start there)'),
))


class _Path(NamedTuple):
    """A projectile's: muzzle (x, y, z) [m], heading (cos, sin), speeds across and up [m/s]."""

    muzzle: tuple[float, float, float]
    direction: tuple[float, float]
    vh: float
    vz: float


class SimTarget:
    """The spinning robot (see the module docstring).

    Attributes:
        shots: projectiles judged; hits: those that hit a plate, by plate index.
    """

    def __init__(self, values: Mapping[str, Any]) -> None:
        self._start = ArmorTarget(
            center=(values['x'], values['y']), z=values['z'],
            velocity=(values['vx'], values['vy'], 0.0), yaw=values['yaw'],
            v_yaw=values['v_yaw'], radius_1=values['radius'], radius_2=values['radius_2'],
            dz=values['dz'], armors_num=values['armors'])
        self._half = (values['width'] / 2, values['height'] / 2)
        self._min_facing = math.cos(values['max_incidence'])
        self.pivot_height: float = values['pivot_height']
        self.barrel_length: float = values['barrel_length']
        self.shots = 0
        self.hits: Counter[int] = Counter()

    def truth(self, now_ns: int) -> ArmorTarget:
        """The target as a perfect tracker would report it at now_ns (plate 0 tracked)."""
        t = now_ns / _NS_PER_S
        s = self._start
        vx, vy, _ = s.velocity
        return ArmorTarget(center=(s.center[0] + vx * t, s.center[1] + vy * t), z=s.z,
                           velocity=s.velocity, yaw=s.yaw + s.v_yaw * t, v_yaw=s.v_yaw,
                           radius_1=s.radius_1, radius_2=s.radius_2, dz=s.dz,
                           armors_num=s.armors_num)

    def plates(self, now_ns: int) -> list[Armor]:
        """Every plate at now_ns."""
        return armors(self._start, now_ns / _NS_PER_S)

    def shoot(self, now_ns: int, pivot: tuple[float, float], yaw: float, pitch: float,
              speed: float) -> int | None:
        """Judge one projectile fired at now_ns; the plate it hit, or None.

        pivot: the gimbal's axes (x, y) in the world [m]; yaw, pitch: the barrel's world
        yaw and REP 103 pitch [rad]; speed: muzzle speed [m/s].
        """
        self.shots += 1
        if not speed > 0.0:
            return None
        elevation = -pitch  # REP 103: positive pitch turns the barrel down
        dx, dy = math.cos(yaw), math.sin(yaw)
        across = self.barrel_length * math.cos(elevation)
        muzzle = (pivot[0] + across * dx, pivot[1] + across * dy,
                  self.pivot_height + self.barrel_length * math.sin(elevation))
        path = _Path(muzzle, (dx, dy), speed * math.cos(elevation), speed * math.sin(elevation))
        best: tuple[float, int] | None = None
        for index in range(self._start.armors_num):
            flight = self._flight(now_ns, index, path)
            if flight is not None and (best is None or flight < best[0]):
                best = (flight, index)
        if best is None:
            return None
        self.hits[best[1]] += 1
        return best[1]

    def _flight(self, now_ns: int, index: int, path: _Path) -> float | None:
        """The flight time to plate index if the projectile hits it, else None."""
        muzzle, (dx, dy), vh, vz = path
        tau = 0.0
        for _ in range(4):  # the plate where the projectile meets it: a fixed point
            plate = self.plates(now_ns + round(tau * _NS_PER_S))[index]
            nx, ny = -math.cos(plate.yaw), -math.sin(plate.yaw)  # its face's normal
            facing = dx * nx + dy * ny
            if facing > -self._min_facing:
                return None  # its back, or seen edge-on
            px, py, pz = plate.position
            s = ((px - muzzle[0]) * nx + (py - muzzle[1]) * ny) / facing
            if s <= 0.0 or vh <= 0.0:
                return None
            tau = s / vh
        hx, hy = muzzle[0] + dx * s, muzzle[1] + dy * s
        hz = muzzle[2] + vz * tau - 0.5 * GRAVITY * tau * tau
        lateral = (hx - px) * -ny + (hy - py) * nx
        if abs(lateral) <= self._half[0] and abs(hz - pz) <= self._half[1]:
            return tau
        return None


def target_from_config(config: Mapping[str, Any]) -> SimTarget:
    """Build the target from the world's ``target`` dict (keys: TARGET_SCHEMA).

    Raises:
        SimConfigError: an unknown or invalid key.
    """
    return SimTarget(TARGET_SCHEMA.read('target', config, SimConfigError))


def muzzle_pose(body: Any) -> tuple[tuple[float, float], float, float]:
    """A simulated body's gimbal axes (x, y), barrel world yaw and REP 103 pitch."""
    return (body.x, body.y), body.yaw + body.gimbal_yaw, body.gimbal_pitch
