"""ShootCmd -> a checked command; the shooter's states and config. No rclpy here."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

from rm_base.control import JamDetectorParams, LookupTable
from rm_base.errors import ConfigError, InputRejectedError

from rm_msgs.msg import ShootCmd, ShooterState


class ShootMode(IntEnum):
    """What the operator asks for (rm_msgs/ShootCmd.mode)."""

    PASSIVE = ShootCmd.PASSIVE  # friction wheels and trigger stopped
    READY = ShootCmd.READY  # wheels at speed, a ball fed, hold fire
    PUSH = ShootCmd.PUSH  # fire the burst


class ShooterStage(IntEnum):
    """What the shooter is doing (rm_msgs/ShooterState.state)."""

    PASSIVE = ShooterState.PASSIVE  # everything off (no command, PASSIVE, or a fault)
    FEED = ShooterState.FEED  # trigger turning (velocity) until the switch sees a ball
    READY = ShooterState.READY  # ball at the switch, trigger holding its position
    PUSH = ShooterState.PUSH  # firing a burst: one slot step (position) per shot
    BLOCK = ShooterState.BLOCK  # jammed: reversing the trigger before feeding again


@dataclass(frozen=True)
class ShootCommand:
    """A checked ShootCmd.

    Attributes:
        mode: PASSIVE, READY or PUSH.
        speed: bullet speed [m/s]; > 0 unless PASSIVE.
        hz: firing rate [shots/s]; > 0 for PUSH.
        num: shots in the burst; 0 = continuous while PUSH is held.
        burst_id: a new value starts a new burst.
    """

    mode: ShootMode
    speed: float
    hz: float
    num: int
    burst_id: int


def parse_shoot_cmd(msg: ShootCmd) -> ShootCommand:
    """Check a ShootCmd and return it as a ShootCommand.

    Raises:
        InputRejectedError: unknown mode, NaN/inf speed or rate, speed <= 0 for READY or
            PUSH, rate <= 0 for PUSH, or a negative speed or rate.
    """
    try:
        mode = ShootMode(msg.mode)
    except ValueError:
        known = ', '.join(f'{m.value} ({m.name})' for m in ShootMode)
        raise InputRejectedError(f'unknown mode {msg.mode} (known: {known})') from None
    speed, hz = float(msg.speed), float(msg.hz)
    for name, value, unit in (('speed', speed, 'm/s'), ('hz', hz, 'shots/s')):
        if not math.isfinite(value):
            raise InputRejectedError(f'{name} must be a finite number [{unit}], got {value}')
        if value < 0.0:
            raise InputRejectedError(f'{name} must be >= 0 {unit}, got {value}')
    if mode is not ShootMode.PASSIVE and speed <= 0.0:
        raise InputRejectedError(f'{mode.name} needs a bullet speed > 0 m/s, got {speed}')
    if mode is ShootMode.PUSH and hz <= 0.0:
        raise InputRejectedError(f'PUSH needs a firing rate hz > 0 shots/s, got {hz}')
    return ShootCommand(mode, speed, hz, int(msg.num), int(msg.burst_id))


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
