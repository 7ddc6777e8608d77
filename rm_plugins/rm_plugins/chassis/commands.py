"""Chassis commands: rm_msgs/ChassisCmd and geometry_msgs/Twist checked into plain values.

A command is used whole or not at all: a NaN/inf field, an unknown mode, follow source or
speed gear rejects the message (``InputRejectedError`` with the reason), and the
plugin keeps acting on the last valid command until that one times out. No ROS here: the
messages are read through their attributes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum, IntEnum
from typing import Any

from rm_base.errors import InputRejectedError
from rm_base.plugin.commands import message_constant


class ChassisMode(IntEnum):
    """States of StandChassis; the values are rm_msgs/ChassisCmd's mode constants."""

    PASSIVE = 0  # wheels limp (zero effort)
    RAW = 1  # /vel_cmd as given, in base_link
    FOLLOW = 2  # translate in the source frame; the chassis turns to follow it
    TWIST = 3  # swing about the source heading while translating in the source frame
    GYRO = 4  # spin while translating in the source frame
    POSITION = 5  # move by (move_x, move_y, move_yaw) and hold (rm_plugins.chassis.position)


class FollowSource(Enum):
    """The frame FOLLOW/TWIST/GYRO translate in and follow (ChassisCmd.follow_source)."""

    GIMBAL = ''  # the gimbal: heading relative to the chassis = the yaw joint angle
    BASE_LINK = 'base_link'  # the robot's own heading when the mode was entered, held in odom
    ODOM = 'odom'  # the world: odom's fixed axes, in every mode (RAW included)


class SpeedGear(IntEnum):
    """ChassisCmd.speed_gear: which coefficients scale /vel_cmd (SRML's speed gears)."""

    NORMAL = 0
    SLOW = 1
    FAST = 2


@dataclass(frozen=True, slots=True)
class ChassisRequest:
    """A checked ChassisCmd.

    Attributes:
        mode: the requested state.
        accel: acceleration limit per axis (vx [m/s²], vy [m/s²], wz [rad/s²]); None where
            the message had <= 0 (use the configured default).
        power_limit: chassis power limit [W]; None if the message had <= 0 (configured).
        source: frame of FOLLOW/TWIST/GYRO.
        gear: the speed gear /vel_cmd is scaled by.
        move: POSITION's (dx [m], dy [m], dyaw [rad]) from where the move starts.
        move_id: a new value starts a new move.
    """

    mode: ChassisMode
    accel: tuple[float | None, float | None, float | None]
    power_limit: float | None
    source: FollowSource
    gear: SpeedGear = SpeedGear.NORMAL
    move: tuple[float, float, float] = (0.0, 0.0, 0.0)
    move_id: int = 0


_SOURCES = {source.value: source for source in FollowSource}
#: Largest POSITION move per axis (x [m], y [m], yaw [rad]): an arena is 28 m by 15 m and a
#: move of more than ten turns is a mistake; beyond them a command is refused at the entry.
MAX_MOVE = (100.0, 100.0, 20.0 * math.pi)
def parse_chassis_cmd(msg: Any) -> ChassisRequest:
    """Check an rm_msgs/ChassisCmd and return it as a ChassisRequest.

    Raises:
        InputRejectedError: unknown mode, follow_source or speed_gear, a NaN/inf number, or
            a move beyond ``MAX_MOVE``.
    """
    mode = message_constant(ChassisMode, msg.mode, 'mode')
    source = _SOURCES.get(msg.follow_source)
    if source is None:
        raise InputRejectedError(
            f"unknown follow_source {msg.follow_source!r} (known: '' = gimbal, 'base_link', "
            "'odom')"
        )
    gear = message_constant(SpeedGear, msg.speed_gear, 'speed_gear')
    raw_accel = (msg.accel.linear.x, msg.accel.linear.y, msg.accel.angular.z)
    numbers = (*raw_accel, msg.power_limit)
    if not all(map(math.isfinite, numbers)):
        raise InputRejectedError(
            f'accel (linear.x, linear.y, angular.z) and power_limit must be finite, got '
            f'{raw_accel} and {msg.power_limit}'
        )
    move = (float(msg.move_x), float(msg.move_y), float(msg.move_yaw))
    if not all(map(math.isfinite, move)):
        raise InputRejectedError(f'move_x, move_y and move_yaw must be finite, got {move}')
    for field, value, limit in zip(('move_x', 'move_y', 'move_yaw'), move, MAX_MOVE, strict=True):
        if abs(value) > limit:
            raise InputRejectedError(f'{field} {value:g} is beyond +-{limit:g}: no move on a field')
    accel = tuple(float(a) if a > 0.0 else None for a in raw_accel)
    power_limit = float(msg.power_limit) if msg.power_limit > 0.0 else None
    return ChassisRequest(
        mode, accel, power_limit, source, gear, move, int(msg.move_id)  # type: ignore[arg-type]
    )


def parse_vel_cmd(msg: Any) -> tuple[float, float, float]:
    """Return (vx [m/s], vy [m/s], wz [rad/s]) of a geometry_msgs/Twist.

    linear.z, angular.x and angular.y are ignored (a chassis moves in the plane).

    Raises:
        InputRejectedError: vx, vy or wz is NaN or infinite.
    """
    values = (float(msg.linear.x), float(msg.linear.y), float(msg.angular.z))
    if not all(map(math.isfinite, values)):
        raise InputRejectedError(
            f'/vel_cmd linear.x, linear.y and angular.z must be finite, got {values}'
        )
    return values
