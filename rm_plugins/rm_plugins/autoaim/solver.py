"""The point to aim at on a tracked robot, predicted over the latency and the flight (pure).

docs/AUTO_AIM.md: the plate facing the shooter (rm_base.geometry.armor_target), or the
centre when the spin is too fast to follow, where it will be once the command has
reached the barrel and the projectile has flown; the flight time comes from the
ballistics of the gimbal's own solver (rm_base.geometry.aim), so the point is solved
twice, the second time with the first solution's flight.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

from rm_base.geometry.aim import aim_from_point
from rm_base.geometry.armor_target import ArmorTarget, center_point, facing_armor
from rm_base.geometry.ballistics import ProjectileModel


@dataclass(frozen=True)
class AimSettings:
    """How to aim.

    Attributes:
        latency_s: from now until the barrel acts on a command [s].
        lead: how far the plate choice leans toward the plate coming into view [rad].
        max_v_yaw: a faster spin is aimed at its centre [rad/s].
        model: the projectile's drag and gravity (the gimbal's).
        barrel_length: pitch axis to muzzle [m].
    """

    latency_s: float = 0.05
    lead: float = 0.26
    max_v_yaw: float = 6.0
    model: ProjectileModel = field(default_factory=ProjectileModel)
    barrel_length: float = 0.0


class AimPoint(NamedTuple):
    """Where to aim.

    Attributes:
        point: in the target's frame [m].
        plate: the plate's index; None: the centre.
        flight_s: the projectile's flight [s].
        distance: horizontal, from the gimbal's axes [m].
    """

    point: tuple[float, float, float]
    plate: int | None
    flight_s: float
    distance: float


def aim_point(target: ArmorTarget, age_s: float, origin: tuple[float, float, float],
              speed: float, settings: AimSettings) -> AimPoint | None:
    """The point to aim at from origin (the gimbal's axes) with a muzzle speed [m/s].

    age_s: how old the target is now [s]. None: out of range at that speed.
    """
    flight = 0.0
    found: AimPoint | None = None
    for _ in range(2):
        ahead = age_s + settings.latency_s + flight
        if abs(target.v_yaw) > settings.max_v_yaw:
            point, plate = center_point(target, ahead), None
        else:
            armor = facing_armor(target, ahead, (origin[0], origin[1]), settings.lead)
            point, plate = armor.position, armor.index
        solution = aim_from_point(origin, point, bullet_speed=speed, model=settings.model,
                                  barrel_length=settings.barrel_length)
        if solution is None:
            return None
        flight = solution.time_of_flight_s or 0.0
        found = AimPoint(point, plate, flight, solution.distance)
    return found
