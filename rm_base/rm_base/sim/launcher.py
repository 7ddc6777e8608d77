"""The shooter's mechanics as the referee's speed module sees them: which pushes are shots.

The trigger (loader wheel) has ``slots`` pockets with a ball in each (an endless hopper,
as the simulated ball switch assumes: rm_plugins.gpio.pins.JointPhaseSwitch). A ball
leaves its pocket into the friction wheels when the trigger turns the pocket past the
firing point, the trigger angle ``k * 2*pi/slots + fire_phase``; it leaves the muzzle at
``speed_ratio`` times the friction wheels' mean speed. A ball pushed out slower than
``min_speed`` (wheels stopped) stays in the barrel: the speed module never sees it, so it
is counted as a dud and not as a shot.

Turning back never un-fires: the furthest pocket pushed out is remembered, so a trigger
that reverses (unjamming) and comes forward again fires only pockets it has not fired.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from rm_base.sim.joint import Joint
from rm_base.sim_devices.device import SimDevice
from rm_base.sim_devices.errors import SimConfigError

CALIBRES = (17, 42)


@dataclass(frozen=True)
class Shot:
    """A projectile that left the muzzle."""

    time_ns: int
    speed_mps: float


class Launcher:
    """Counts the projectiles the simulated shooter fires (see the module docstring).

    Attributes:
        calibre: 17 or 42 [mm].
        shots: projectiles fired so far.
        duds: balls pushed out too slowly to leave the barrel.
    """

    def __init__(
        self,
        trigger: Joint,
        friction: Sequence[Joint],
        *,
        slots: int,
        fire_phase: float,
        speed_ratio: float,
        min_speed: float = 5.0,
        calibre: int = 17,
    ) -> None:
        """Raises: SimConfigError: bad geometry or calibre."""
        if isinstance(slots, bool) or not isinstance(slots, int) or slots < 1:
            raise SimConfigError(f'shooter slots must be an integer >= 1, got {slots!r}')
        self.slot_angle = 2.0 * math.pi / slots
        if not (math.isfinite(fire_phase) and 0.0 <= fire_phase < self.slot_angle):
            raise SimConfigError(
                f'shooter fire_phase must lie in [0, 2*pi/slots), got {fire_phase!r}'
            )
        for name, value in (('speed_ratio', speed_ratio), ('min_speed', min_speed)):
            if not (math.isfinite(value) and value >= 0.0):
                raise SimConfigError(f'shooter {name} must be >= 0, got {value!r}')
        if calibre not in CALIBRES:
            raise SimConfigError(f'shooter calibre must be 17 or 42 (mm), got {calibre!r}')
        if not friction:
            raise SimConfigError('a shooter needs at least one friction wheel')
        self.trigger = trigger
        self.friction = tuple(friction)
        self.fire_phase = float(fire_phase)
        self.speed_ratio = float(speed_ratio)
        self.min_speed = float(min_speed)
        self.calibre = calibre
        self.shots = 0
        self.duds = 0
        self._fired = self._pocket()

    @property
    def devices(self) -> tuple[SimDevice, ...]:
        """The motors of the shooter (the referee's shooter port powers them)."""
        return (self.trigger.device, *(joint.device for joint in self.friction))

    def muzzle_speed(self) -> float:
        """The speed a ball pushed out now leaves at [m/s] (0 if the wheels turn backwards)."""
        mean = sum(joint.velocity for joint in self.friction) / len(self.friction)
        return max(0.0, self.speed_ratio * mean)

    def update(self, now_ns: int) -> list[Shot]:
        """The projectiles fired since the last update (after a physics step)."""
        pocket = self._pocket()
        if pocket <= self._fired:
            return []
        pushed, self._fired = pocket - self._fired, pocket
        speed = self.muzzle_speed()
        if speed < self.min_speed:
            self.duds += pushed
            return []
        self.shots += pushed
        return [Shot(now_ns, speed)] * pushed

    def _pocket(self) -> int:
        return math.floor((self.trigger.angle - self.fire_phase) / self.slot_angle)
