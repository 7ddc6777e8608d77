"""ShootCmd -> a checked command, and the shooter's states. No rclpy here."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

from rm_base.errors import InputRejectedError
from rm_base.plugin.commands import message_constant

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
    mode = message_constant(ShootMode, msg.mode, 'mode')
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
