"""The shooter's configuration: what it holds, and reading it from the parameters."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rm_base.control import LookupTable
from rm_base.errors import ConfigError
from rm_base.plugin import PluginParams

from rm_plugins.shooter.barrel_heat import (
    HEAT_PER_17MM_SHOT,
    HEAT_PER_42MM_SHOT,
    BarrelHeatParams,
)
from rm_plugins.shooter.jam_detector import JamDetectorParams


@dataclass(frozen=True)
class ShooterConfig:
    """Everything the shooter is configured with (SI units; see StandShooter's docstring).

    Attributes:
        friction_joints: friction wheel joints.
        friction_directions: per wheel, +1 or -1: the sign of the joint velocity that
            launches a ball.
        trigger_joint: the trigger (loader) joint.
        trigger_direction: +1 or -1: the sign of the joint motion that feeds balls.
        wheel_speed: bullet speed [m/s] -> friction wheel speed [rad/s].
        friction_tolerance: a wheel is at speed within this of its target [rad/s].
        slots: trigger pockets per turn; one shot is one slot step of 2*pi/slots.
        feed_speed: trigger speed while feeding [rad/s], > 0.
        step_speed: trigger speed of a slot step [rad/s], > 0: the setpoint moves from the
            hold to the step's end at this speed, which is also the velocity feed-forward.
        step_tolerance: a slot step (or the reverse) is done within this [rad].
        max_hz: highest firing rate; faster commands are limited to it [shots/s].
        limit_switch: name of the ball switch on /gpio_state.
        switch_timeout: an older switch state is unknown [s].
        switch_debounce: between shots, "no ball" must last this long before FEED [s].
        jam: when the trigger counts as jammed.
        reverse_angle: how far BLOCK turns the trigger back [rad], > 0.
        block_timeout: longest reverse before feeding again [s].
        jam_retries: BLOCK recoveries tried after jams in a row; one more jam is a fault.
        state_rate: rate of /shooter_state [Hz] (plus on every change).
        heat_calibre: the barrel whose heat the shooter keeps under the referee's limit,
            17 or 42 [mm]; 0: no heat limit (no referee system).
        heat: how it keeps the heat under the limit (None with heat_calibre 0).
        referee_timeout: no /referee/robot_status this long: heat's fallback limits [s].
    """

    friction_joints: tuple[str, ...]
    friction_directions: tuple[float, ...]
    trigger_joint: str
    trigger_direction: float
    wheel_speed: LookupTable
    friction_tolerance: float
    slots: int
    feed_speed: float
    step_speed: float
    step_tolerance: float
    max_hz: float
    limit_switch: str
    switch_timeout: float
    switch_debounce: float
    jam: JamDetectorParams
    reverse_angle: float
    block_timeout: float
    jam_retries: int
    state_rate: float
    heat_calibre: int = 0
    heat: BarrelHeatParams | None = None
    referee_timeout: float = 1.0

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

    @property
    def slot_angle(self) -> float:
        """Trigger angle of one shot: 2*pi / slots [rad]."""
        return 2.0 * math.pi / self.slots


def read_config(p: PluginParams) -> ShooterConfig:
    """Declare and read the shooter's parameters (``<name>.<key>``; see the robot configs).

    Raises:
        ParameterError: a parameter is missing or out of its bounds.
        ConfigError: the values do not fit together (ShooterConfig).
    """
    friction_joints = p.string_array(
        'friction_joints', description='friction wheel joints', unique=True
    )
    friction_directions = p.double_array(
        'friction_directions',
        description='per friction wheel, the sign (+1/-1) of the joint velocity that '
        'launches a ball',
    )
    bullet_speeds = p.double_array(
        'bullet_speeds',
        description='bullet speeds of the lookup table (x, increasing)',
        unit='m/s',
        gt=0.0,
    )
    wheel_speeds = p.double_array(
        'wheel_speeds',
        description='friction wheel speed giving each of bullet_speeds',
        unit='rad/s',
        gt=0.0,
    )
    return ShooterConfig(
        friction_joints=friction_joints,
        friction_directions=friction_directions,
        trigger_joint=p.string('trigger_joint', description='trigger (loader) joint'),
        trigger_direction=p.double(
            'trigger_direction',
            1.0,
            description='sign (+1/-1) of the trigger motion that feeds balls',
        ),
        wheel_speed=LookupTable.from_columns(bullet_speeds, wheel_speeds),
        friction_tolerance=p.double(
            'friction_tolerance',
            description='a friction wheel is at speed within this of its target',
            unit='rad/s',
            gt=0.0,
        ),
        slots=p.integer('slots', description='trigger pockets per turn', ge=1),
        feed_speed=p.double(
            'feed_speed', description='trigger speed while feeding', unit='rad/s', gt=0.0
        ),
        step_speed=p.double(
            'step_speed',
            description='trigger speed of a slot step (setpoint ramp and feed-forward)',
            unit='rad/s',
            gt=0.0,
        ),
        step_tolerance=p.double(
            'step_tolerance',
            description='a slot step or the reverse is done within this',
            unit='rad',
            gt=0.0,
        ),
        max_hz=p.double('max_hz', description='highest firing rate', unit='shots/s', gt=0.0),
        limit_switch=p.string(
            'limit_switch', description='name of the ball switch on /gpio_state'
        ),
        switch_timeout=p.double(
            'switch_timeout',
            0.2,
            description='an older limit switch state is unknown',
            unit='s',
            gt=0.0,
        ),
        switch_debounce=p.double(
            'switch_debounce',
            0.05,
            description='between shots, the switch must read "no ball" this long '
            'before the trigger feeds again',
            unit='s',
            ge=0.0,
        ),
        jam=JamDetectorParams(
            effort_threshold=p.double(
                'jam.effort',
                description='trigger effort above which it may be jammed',
                unit='N*m',
                gt=0.0,
            ),
            speed_threshold=p.double(
                'jam.speed',
                description='trigger speed below which it may be jammed',
                unit='rad/s',
                gt=0.0,
            ),
            time_s=p.double(
                'jam.time',
                description='how long both must hold to be a jam',
                unit='s',
                gt=0.0,
            ),
        ),
        reverse_angle=p.double(
            'reverse_angle',
            description='how far the trigger turns back after a jam',
            unit='rad',
            gt=0.0,
        ),
        block_timeout=p.double(
            'block_timeout',
            description='longest reverse before feeding again',
            unit='s',
            gt=0.0,
        ),
        jam_retries=p.integer(
            'jam_retries',
            description='recoveries tried after jams in a row before giving up (fault)',
            ge=0,
        ),
        state_rate=p.double(
            'state_rate', 50.0, description='rate of /shooter_state', unit='Hz', gt=0.0
        ),
        **_heat_config(p),
    )


def _heat_config(p: PluginParams) -> dict[str, Any]:
    """The barrel heat limit's parameters (``heat.*``), declared whether it is on or not."""
    calibre = p.integer(
        'heat.calibre', 0, ge=0, le=42,
        description='keep the heat of this barrel under the referee limit: 17 or 42 (mm); '
        '0: no heat limit (no referee system)',
    )
    if calibre not in (0, 17, 42):
        raise ConfigError(f'heat.calibre must be 0, 17 or 42, got {calibre}')
    per_shot = HEAT_PER_42MM_SHOT if calibre == 42 else HEAT_PER_17MM_SHOT
    margin = p.double(
        'heat.margin', per_shot, ge=0.0,
        description='heat kept free under the limit for shots the referee has not counted yet '
        '(default: one shot)',
    )
    fallback_limit = p.double(
        'heat.fallback_limit', 5 * per_shot, gt=0.0,
        description='heat limit while the referee is silent: conservative, never none',
    )
    fallback_cooling = p.double(
        'heat.fallback_cooling', per_shot, ge=0.0, unit='1/s',
        description='cooling per second assumed while the referee is silent',
    )
    timeout = p.double(
        'heat.referee_timeout', 1.0, gt=0.0, unit='s',
        description='no /referee/robot_status this long -> the fallback limits',
    )
    heat = None
    if calibre:
        heat = BarrelHeatParams(per_shot, margin, fallback_limit, fallback_cooling)
    return {'heat_calibre': calibre, 'heat': heat, 'referee_timeout': timeout}
