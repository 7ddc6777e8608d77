"""Gimbal commands: rm_msgs/GimbalCmd checked once into a GimbalRequest.

A message is used whole or not at all: an unknown mode, a NaN/inf rate, target or bullet
speed, or a target or speed beyond what a field holds is an ``InputRejectedError`` with
the reason. No ROS here: the message is read through its attributes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

from rm_base.errors import InputRejectedError
from rm_base.plugin.commands import message_constant

#: Farthest TRACK target per axis [m] and fastest bullet [m/s] a command may give.
MAX_TARGET_DISTANCE = 1000.0
MAX_BULLET_SPEED = 100.0


class GimbalMode(IntEnum):
    """States of the gimbal plugin; values are GimbalCmd's modes."""

    PASSIVE = 0
    RATE = 1
    TRACK = 2


@dataclass(frozen=True, slots=True)
class GimbalRequest:
    """A checked GimbalCmd.

    Attributes:
        mode: the requested state.
        rates: RATE's (yaw, pitch) world rates [rad/s].
        target: TRACK's point (x, y, z) [m] in frame.
        frame: the target's frame id.
        bullet_speed: TRACK's bullet speed [m/s]; 0: no drop compensation.
    """

    mode: GimbalMode
    rates: tuple[float, float] = (0.0, 0.0)
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    frame: str = ''
    bullet_speed: float = 0.0


def parse_gimbal_cmd(msg: Any) -> GimbalRequest:
    """Check an rm_msgs/GimbalCmd and return it as a GimbalRequest.

    Raises:
        InputRejectedError: unknown mode; for RATE a rate, for TRACK the target or the
            bullet speed, not finite or beyond ``MAX_TARGET_DISTANCE`` / ``MAX_BULLET_SPEED``.
    """
    mode = message_constant(GimbalMode, msg.mode, 'mode')
    if mode is GimbalMode.PASSIVE:
        return GimbalRequest(mode)
    if mode is GimbalMode.RATE:
        rates = (float(msg.rate_yaw), float(msg.rate_pitch))
        if not all(map(math.isfinite, rates)):
            raise InputRejectedError(f'rate_yaw and rate_pitch must be finite, got {rates}')
        return GimbalRequest(mode, rates=rates)
    point = msg.target.point
    target = (float(point.x), float(point.y), float(point.z))
    speed = float(msg.bullet_speed)
    if not all(map(math.isfinite, (*target, speed))):
        raise InputRejectedError(
            f'target {target} and bullet_speed {speed} must be finite'
        )
    if max(map(abs, target)) > MAX_TARGET_DISTANCE or abs(speed) > MAX_BULLET_SPEED:
        raise InputRejectedError(
            f'target ({target[0]:g}, {target[1]:g}, {target[2]:g}) m or bullet speed '
            f'{speed:g} m/s beyond {MAX_TARGET_DISTANCE:g} m / {MAX_BULLET_SPEED:g} m/s'
        )
    return GimbalRequest(mode, target=target, frame=msg.target.header.frame_id,
                         bullet_speed=speed)
