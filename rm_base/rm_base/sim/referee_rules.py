"""The referee's game rules for one robot: barrel heat, buffer energy, HP and its outputs.

Pure and stepped by the caller: :meth:`RefereeRules.shot` for every projectile the speed
module sees, :meth:`RefereeRules.step` every 100 ms with the chassis power measured over
that period. docs/PROTOCOLS.md §6.6 gives the rules and where they come from:

* heat: +10 per 17 mm and +100 per 42 mm projectile; each 100 ms step cools by
  ``cooling / 10``, never below 0.
* over the heat limit Q0, by season. 2024: Q0 < Q1 < 2 Q0 costs ``(Q1 - Q0) / 250 / 10``
  of max HP per step; Q1 >= 2 Q0 (every season) costs ``(Q1 - 2 Q0) / 250`` at once and
  sets Q1 = 2 Q0. 2025 and 2026: Q1 > Q0 locks the launcher (its output off) until Q1 is
  back at 0; Q1 > Q0 + 100 (17 mm) or + 200 (42 mm) locks it for the rest of the match.
* buffer energy (cap 60 J): each step ``buffer -= (P - limit) * 0.1``, refilling at the
  same rate below the limit. With the buffer used up, 2024 costs ``max HP * N % * 0.1`` a
  step (N = 10 / 20 / 40 for an excess up to 10 % / 20 % / more of the limit); 2025 and
  2026 cut the chassis output for 5 s.
* HP 0: every output off for the rest of the match.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rm_base.hardware.protocols.referee import (
    Hurt,
    PowerHeat,
    ProjectileAllowance,
    ProtocolVersion,
    RobotStatus,
    ShootData,
)
from rm_base.sim_devices.errors import SimConfigError

_NS_PER_S = 1_000_000_000
#: The referee's rule period [s].
STEP_S = 0.1
STEP_NS = round(STEP_S * _NS_PER_S)
HEAT_PER_SHOT = {17: 10, 42: 100}
#: Heat above the limit that locks the launcher for the match (2025 on).
LOCK_FOR_MATCH_MARGIN = {17: 100, 42: 200}
#: 0x0206 causes (docs/PROTOCOLS.md §6.2).
HURT_OVER_HEAT = 3
HURT_OVER_POWER = 4
#: 0x0207 bullet types.
BULLET_TYPE = {17: 1, 42: 2}


@dataclass(frozen=True)
class RefereeSettings:
    """What the referee sets for the simulated robot (its 0x0201) and how it judges.

    Attributes:
        version: the season's rules and frame layouts.
        robot_id: 1 hero, 3-5 infantry, 7 sentry... (blue = red + 100).
        level: robot level.
        max_hp: HP at the start.
        heat_limit: barrel heat limit Q0.
        cooling_per_s: barrel cooling value.
        chassis_power_limit_w: chassis power limit [W].
        buffer_max_j: buffer energy cap [J] (60).
        calibre: the launcher's calibre, 17 or 42 [mm].
        allowance: projectiles the robot may fire.
        chassis_cut_s: how long an empty buffer cuts the chassis (2025 on) [s].
    """

    version: ProtocolVersion = ProtocolVersion.V2026
    robot_id: int = 3
    level: int = 1
    max_hp: int = 200
    heat_limit: int = 100
    cooling_per_s: int = 10
    chassis_power_limit_w: float = 60.0
    buffer_max_j: float = 60.0
    calibre: int = 17
    allowance: int = 500
    chassis_cut_s: float = 5.0

    def __post_init__(self) -> None:
        if self.calibre not in HEAT_PER_SHOT:
            raise SimConfigError(f'referee calibre must be 17 or 42 (mm), got {self.calibre!r}')
        for name in ('robot_id', 'level', 'max_hp', 'heat_limit', 'cooling_per_s', 'allowance'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 0xFFFF:
                raise SimConfigError(
                    f'referee {name} must be an integer in [0, 65535], got {value!r}'
                )
        if self.max_hp < 1 or not 1 <= self.robot_id <= 0xFF:
            raise SimConfigError('referee max_hp must be >= 1 and robot_id in [1, 255]')
        for name in ('chassis_power_limit_w', 'buffer_max_j', 'chassis_cut_s'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not (
                math.isfinite(value) and 0.0 <= value <= 0xFFFF
            ):
                raise SimConfigError(
                    f'referee {name} must be a number in [0, 65535], got {value!r}'
                )


@dataclass(frozen=True)
class Outputs:
    """The power-management module's 24 V outputs."""

    gimbal: bool = True
    chassis: bool = True
    shooter: bool = True


class RefereeRules:
    """One robot as the referee keeps it (see the module docstring).

    Attributes:
        settings: the limits and the season.
        hp: current HP.
        heat: barrel heat Q1 (float; sent rounded).
        buffer_j: buffer energy [J].
        power_w: chassis power of the last step [W].
        chassis_cuts: times an empty buffer cut the chassis (2025 on).
        launcher_locks: times the heat locked the launcher (2025 on).
        shots: projectiles counted.
        revivals: times :meth:`revive` brought the robot back.
    """

    def __init__(self, settings: RefereeSettings) -> None:
        self.settings = settings
        self.hp = settings.max_hp
        self.heat = 0.0
        self.buffer_j = settings.buffer_max_j
        self.power_w = 0.0
        self.allowance = settings.allowance
        self.chassis_cuts = 0
        self.launcher_locks = 0
        self.shots = 0
        self.revivals = 0
        self._cut_until_ns: int | None = None
        self._locked = False
        self._locked_for_match = False
        self._last_shot_ns: int | None = None

    @property
    def _since_2025(self) -> bool:
        return self.settings.version is not ProtocolVersion.V2024

    # -- events ------------------------------------------------------------------------------

    def shot(self, now_ns: int, speed_mps: float) -> ShootData:
        """A projectile the speed module saw: its heat counts at once."""
        s = self.settings
        self.shots += 1
        self.heat += HEAT_PER_SHOT[s.calibre]
        self.allowance = max(0, self.allowance - 1)
        frequency = 0
        if self._last_shot_ns is not None and now_ns > self._last_shot_ns:
            frequency = min(255, round(_NS_PER_S / (now_ns - self._last_shot_ns)))
        self._last_shot_ns = now_ns
        self._judge_heat_lock()
        return ShootData(BULLET_TYPE[s.calibre], 1, frequency, speed_mps)

    def step(self, now_ns: int, chassis_power_w: float) -> list[Hurt]:
        """One 100 ms rule period ending at now_ns; the hurts it dealt (0x0206 to send).

        chassis_power_w: the chassis output's mean power over the period [W].
        """
        s = self.settings
        hurts: list[Hurt] = []
        self.power_w = chassis_power_w
        self.heat = max(0.0, self.heat - s.cooling_per_s * STEP_S)
        if self._cut_until_ns is not None and now_ns >= self._cut_until_ns:
            self._cut_until_ns = None
        excess = chassis_power_w - s.chassis_power_limit_w
        self.buffer_j = min(s.buffer_max_j, max(0.0, self.buffer_j - excess * STEP_S))
        if self.buffer_j <= 0.0 and excess > 0.0:
            if self._since_2025:
                if self._cut_until_ns is None:
                    self._cut_until_ns = now_ns + round(s.chassis_cut_s * _NS_PER_S)
                    self.chassis_cuts += 1
            else:
                ratio = excess / s.chassis_power_limit_w if s.chassis_power_limit_w else math.inf
                percent = 10 if ratio <= 0.1 else 20 if ratio <= 0.2 else 40
                self._hurt(s.max_hp * percent / 100.0 * STEP_S, HURT_OVER_POWER, hurts)
        self._judge_heat(hurts)
        return hurts

    @property
    def destroyed(self) -> bool:
        """No HP left: every output is off until :meth:`revive`."""
        return self.hp <= 0

    @property
    def locked_for_match(self) -> bool:
        """The heat went so far over the limit that the launcher stays off (2025 on)."""
        return self._locked_for_match

    def revive(self) -> None:
        """Bring the robot back as it started (a revival).

        Full HP, a cold barrel, a full buffer, no cut and no lock; the soak uses it so that
        one destruction does not end its run.
        """
        s = self.settings
        self.hp = s.max_hp
        self.heat = 0.0
        self.buffer_j = s.buffer_max_j
        self._cut_until_ns = None
        self._locked = self._locked_for_match = False
        self.revivals += 1

    # -- what the referee reports -----------------------------------------------------------------

    @property
    def outputs(self) -> Outputs:
        """Which outputs are on now."""
        if self.hp <= 0:
            return Outputs(False, False, False)
        return Outputs(
            gimbal=True,
            chassis=self._cut_until_ns is None,
            shooter=not (self._locked or self._locked_for_match),
        )

    def robot_status(self) -> RobotStatus:
        """0x0201 now."""
        s, out = self.settings, self.outputs
        return RobotStatus(
            s.robot_id, s.level, self.hp, s.max_hp, s.cooling_per_s, s.heat_limit,
            float(s.chassis_power_limit_w), out.gimbal, out.chassis, out.shooter,
        )

    def power_heat(self) -> PowerHeat:
        """0x0202 now (the chassis electrics only in 2024's layout)."""
        heat = min(0xFFFF, round(self.heat))
        heat_17, heat_42 = (heat, 0) if self.settings.calibre == 17 else (0, heat)
        if self._since_2025:
            return PowerHeat(math.floor(self.buffer_j), heat_17, heat_42)
        volts = 24.0
        return PowerHeat(
            math.floor(self.buffer_j), heat_17, heat_42, 0, volts, self.power_w / volts,
            self.power_w,
        )

    def projectile_allowance(self) -> ProjectileAllowance:
        """0x0208 now."""
        n = min(0xFFFF, self.allowance)
        mine = (n, 0) if self.settings.calibre == 17 else (0, n)
        return ProjectileAllowance(*mine, 0, None if not self._since_2025 else 0)

    # -- rules ------------------------------------------------------------------------------------

    def _judge_heat(self, hurts: list[Hurt]) -> None:
        s = self.settings
        limit = s.heat_limit
        if self.heat >= 2 * limit:
            self._hurt((self.heat - 2 * limit) / 250.0 * s.max_hp, HURT_OVER_HEAT, hurts)
            self.heat = float(2 * limit)
        elif self.heat > limit and not self._since_2025:
            self._hurt((self.heat - limit) / 250.0 / 10.0 * s.max_hp, HURT_OVER_HEAT, hurts)
        self._judge_heat_lock()

    def _judge_heat_lock(self) -> None:
        if not self._since_2025:
            return
        limit = self.settings.heat_limit
        if self.heat > limit + LOCK_FOR_MATCH_MARGIN[self.settings.calibre]:
            self._locked_for_match = True
        if self.heat > limit and not self._locked:
            self._locked = True
            self.launcher_locks += 1
        elif self._locked and self.heat <= 0.0:
            self._locked = False

    def _hurt(self, amount: float, cause: int, hurts: list[Hurt]) -> None:
        if amount <= 0.0:
            return
        self.hp = max(0, self.hp - math.ceil(amount))
        hurts.append(Hurt(0, cause))
