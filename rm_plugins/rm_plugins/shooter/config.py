"""The shooter's parameters, declared once: each field is a key (``shooter.<field>``).

The fields are the typed values; the keys' types, units, bounds, defaults and
descriptions make the ROS declarations, the errors naming a key and the rows of
docs/PARAMETERS.md (:func:`rm_base.config.schema.declare`). What follows from them (the
speed lookup table, the jam detector's and the heat limit's settings) are properties.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from rm_base.config.schema import declare, group, integer, number, numbers, one_of, string, strings
from rm_base.control import LookupTable
from rm_base.errors import ConfigError

from rm_plugins.shooter.barrel_heat import (
    HEAT_PER_17MM_SHOT,
    HEAT_PER_42MM_SHOT,
    BarrelHeatParams,
)
from rm_plugins.shooter.jam_detector import JamDetectorParams


@dataclass(frozen=True, kw_only=True)
class JamParams:
    """When the trigger counts as jammed (``shooter.jam.*``)."""

    effort: float = declare(
        number,
        tunable=True,
        description='trigger effort above which it may be jammed',
        unit='N*m',
        gt=0.0,
    )
    speed: float = declare(
        number,
        tunable=True,
        description='trigger speed below which it may be jammed',
        unit='rad/s',
        gt=0.0,
    )
    time: float = declare(
        number, tunable=True, description='how long both must hold to be a jam', unit='s', gt=0.0
    )


@dataclass(frozen=True, kw_only=True)
class HeatParams:
    """How the barrel's heat is kept under the referee's limit (``shooter.heat.*``)."""

    calibre: int = declare(
        one_of,
        0,
        choices=(0, 17, 42),
        description='keep the heat of this barrel under the referee limit: 17 or 42 (mm); '
        '0: no heat limit (no referee system)',
    )
    margin: float | None = declare(
        number,
        None,
        tunable=True,
        ge=0.0,
        description='heat kept free under the limit for shots the referee has not counted yet '
        '(unset: one shot)',
    )
    fallback_limit: float | None = declare(
        number,
        None,
        tunable=True,
        gt=0.0,
        description='heat limit while the referee is silent: conservative, never none '
        '(unset: five shots)',
    )
    fallback_cooling: float | None = declare(
        number,
        None,
        tunable=True,
        ge=0.0,
        unit='1/s',
        description='cooling per second assumed while the referee is silent (unset: one shot)',
    )
    referee_timeout: float = declare(
        number,
        1.0,
        gt=0.0,
        unit='s',
        description='no /referee/robot_status this long -> the fallback limits',
    )

    @property
    def per_shot(self) -> float:
        """Heat one projectile of this calibre adds."""
        return HEAT_PER_42MM_SHOT if self.calibre == 42 else HEAT_PER_17MM_SHOT

    @property
    def barrel(self) -> BarrelHeatParams | None:
        """The heat limit's settings; None without a heat limit (calibre 0)."""
        if not self.calibre:
            return None
        shot = self.per_shot
        return BarrelHeatParams(
            shot,
            shot if self.margin is None else self.margin,
            5 * shot if self.fallback_limit is None else self.fallback_limit,
            shot if self.fallback_cooling is None else self.fallback_cooling,
        )


@dataclass(frozen=True, kw_only=True)
class ShooterConfig:
    """Everything the shooter is configured with (SI units; each field's key says what)."""

    friction_joints: tuple[str, ...] = declare(
        strings, description='friction wheel joints', unique=True
    )
    friction_directions: tuple[float, ...] = declare(
        numbers,
        description='per friction wheel, the sign (+1/-1) of the joint velocity that '
        'launches a ball',
    )
    bullet_speeds: tuple[float, ...] = declare(
        numbers,
        tunable=True,
        description='bullet speeds of the lookup table (x, increasing)',
        unit='m/s',
        gt=0.0,
    )
    wheel_speeds: tuple[float, ...] = declare(
        numbers,
        tunable=True,
        description='friction wheel speed giving each of bullet_speeds',
        unit='rad/s',
        gt=0.0,
    )
    trigger_joint: str = declare(string, description='trigger (loader) joint')
    trigger_direction: float = declare(
        number, 1.0, description='sign (+1/-1) of the trigger motion that feeds balls'
    )
    friction_tolerance: float = declare(
        number,
        tunable=True,
        description='a friction wheel is at speed within this of its target',
        unit='rad/s',
        gt=0.0,
    )
    slots: int = declare(integer, description='trigger pockets per turn', ge=1)
    feed_speed: float = declare(
        number, tunable=True, description='trigger speed while feeding', unit='rad/s', gt=0.0
    )
    step_speed: float = declare(
        number,
        tunable=True,
        description='trigger speed of a slot step (setpoint ramp and feed-forward)',
        unit='rad/s',
        gt=0.0,
    )
    step_tolerance: float = declare(
        number,
        tunable=True,
        description='a slot step or the reverse is done within this',
        unit='rad',
        gt=0.0,
    )
    max_hz: float = declare(
        number, tunable=True, description='highest firing rate', unit='shots/s', gt=0.0
    )
    limit_switch: str = declare(string, description='name of the ball switch on /gpio_state')
    switch_timeout: float = declare(
        number, 0.2, description='an older limit switch state is unknown', unit='s', gt=0.0
    )
    switch_debounce: float = declare(
        number,
        0.05,
        tunable=True,
        description='between shots, the switch must read "no ball" this long before the '
        'trigger feeds again',
        unit='s',
        ge=0.0,
    )
    jam: JamParams = group(JamParams)
    reverse_angle: float = declare(
        number,
        tunable=True,
        description='how far the trigger turns back after a jam',
        unit='rad',
        gt=0.0,
    )
    block_timeout: float = declare(
        number, tunable=True, description='longest reverse before feeding again', unit='s', gt=0.0
    )
    jam_retries: int = declare(
        integer,
        tunable=True,
        description='recoveries tried after jams in a row before giving up (fault)',
        ge=0,
    )
    state_rate: float = declare(
        number, 50.0, tunable=True, description='rate of /shooter_state', unit='Hz', gt=0.0
    )
    heat: HeatParams = group(HeatParams)

    def __post_init__(self) -> None:
        if not self.friction_joints:
            raise ConfigError('friction_joints: at least one friction wheel is needed')
        if len(self.friction_directions) != len(self.friction_joints):
            raise ConfigError(
                f'friction_directions has {len(self.friction_directions)} entries for '
                f'{len(self.friction_joints)} friction_joints'
            )
        for name, values in (
            ('friction_directions', self.friction_directions),
            ('trigger_direction', (self.trigger_direction,)),
        ):
            if any(v not in (1.0, -1.0) for v in values):
                raise ConfigError(f'{name} must be +1 or -1, got {values}')
        if self.trigger_joint in self.friction_joints:
            raise ConfigError(f'trigger_joint {self.trigger_joint!r} is also a friction joint')
        if not self.wheel_speed.increasing:
            raise ConfigError('wheel_speeds must increase with bullet_speeds')
        if self.step_tolerance >= self.slot_angle / 2.0:
            raise ConfigError(
                f'step_tolerance {self.step_tolerance} rad must be below half a slot '
                f'({self.slot_angle / 2.0:.4f} rad)'
            )

    @cached_property
    def wheel_speed(self) -> LookupTable:
        """Bullet speed [m/s] -> friction wheel speed [rad/s]."""
        return LookupTable.from_columns(self.bullet_speeds, self.wheel_speeds)

    @property
    def slot_angle(self) -> float:
        """Trigger angle of one shot: 2*pi / slots [rad]."""
        return 2.0 * math.pi / self.slots

    @property
    def jam_detector(self) -> JamDetectorParams:
        """The jam detector's settings."""
        return JamDetectorParams(self.jam.effort, self.jam.speed, self.jam.time)
