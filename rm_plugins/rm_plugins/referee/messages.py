"""Referee records (``rm_base.hardware.protocols.referee``) -> rm_msgs messages, SI units.

What the protocol leaves out in a season (the chassis electrics from 2025 on, a second
17 mm heat in 2026, the bullet speed limit before 2026 V2.0) is NaN, never 0: a 0 W limit
or 0 heat would be read as data.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from rm_base.hardware.protocols import referee as ref

from rm_msgs.msg import (
    RefereeGameStatus,
    RefereeHurt,
    RefereeKeyboardMouse,
    RefereePowerHeat,
    RefereeProjectiles,
    RefereeRobotStatus,
    RefereeShot,
)


def _or_nan(value: float | None) -> float:
    return math.nan if value is None else float(value)


def game_status(r: ref.GameStatus) -> RefereeGameStatus:
    """0x0001 as a message."""
    return RefereeGameStatus(
        game_type=r.game_type, progress=r.progress, stage_remaining=r.stage_remaining_s,
        unix_time=r.unix_time,
    )


def robot_status(r: ref.RobotStatus) -> RefereeRobotStatus:
    """0x0201 as a message."""
    return RefereeRobotStatus(
        robot_id=r.robot_id, level=r.level, hp=r.hp, max_hp=r.max_hp,
        barrel_cooling=float(r.barrel_cooling_per_s),
        barrel_heat_limit=float(r.barrel_heat_limit),
        chassis_power_limit=r.chassis_power_limit_w,
        gimbal_power=r.gimbal_power, chassis_power=r.chassis_power,
        shooter_power=r.shooter_power, bullet_speed_limit=_or_nan(r.bullet_speed_limit_mps),
    )


def power_heat(r: ref.PowerHeat) -> RefereePowerHeat:
    """0x0202 as a message."""
    return RefereePowerHeat(
        buffer_energy=r.buffer_energy_j, heat_17mm=float(r.heat_17mm),
        heat_17mm_2=_or_nan(r.heat_17mm_2), heat_42mm=float(r.heat_42mm),
        chassis_voltage=_or_nan(r.chassis_voltage_v),
        chassis_current=_or_nan(r.chassis_current_a),
        chassis_power=_or_nan(r.chassis_power_w),
    )


def shot(r: ref.ShootData) -> RefereeShot:
    """0x0207 as a message."""
    return RefereeShot(
        bullet_type=r.bullet_type, launcher_id=r.launcher_id,
        frequency=float(r.frequency_hz), speed=r.speed_mps,
    )


def projectiles(r: ref.ProjectileAllowance) -> RefereeProjectiles:
    """0x0208 as a message."""
    return RefereeProjectiles(
        allowance_17mm=r.allowance_17mm, allowance_42mm=r.allowance_42mm, gold=r.gold,
        fortress_17mm=r.fortress_17mm or 0,
    )


def hurt(r: ref.Hurt) -> RefereeHurt:
    """0x0206 as a message."""
    return RefereeHurt(armor_id=r.armor_id, cause=r.cause)


def keyboard_mouse(r: ref.KeyboardMouse) -> RefereeKeyboardMouse:
    """0x0304 as a message."""
    return RefereeKeyboardMouse(
        mouse_x=r.mouse_x, mouse_y=r.mouse_y, mouse_wheel=r.mouse_wheel, left=r.left,
        right=r.right, keys=r.keys,
    )


def remote_keyboard_mouse(r: ref.RemoteFrame) -> RefereeKeyboardMouse:
    """The keyboard and mouse of an A9 53 remote frame (its sticks are the DR16's job)."""
    return RefereeKeyboardMouse(
        mouse_x=r.mouse_x, mouse_y=r.mouse_y, mouse_wheel=r.mouse_wheel, left=r.mouse_left,
        right=r.mouse_right, keys=r.keys,
    )


#: Record type -> (topic, message type, converter).
TOPICS: dict[type, tuple[str, type, Callable[[Any], Any]]] = {
    ref.GameStatus: ('referee/game_status', RefereeGameStatus, game_status),
    ref.RobotStatus: ('referee/robot_status', RefereeRobotStatus, robot_status),
    ref.PowerHeat: ('referee/power_heat', RefereePowerHeat, power_heat),
    ref.ShootData: ('referee/shot', RefereeShot, shot),
    ref.ProjectileAllowance: ('referee/projectiles', RefereeProjectiles, projectiles),
    ref.Hurt: ('referee/hurt', RefereeHurt, hurt),
    ref.KeyboardMouse: ('referee/keyboard_mouse', RefereeKeyboardMouse, keyboard_mouse),
    ref.RemoteFrame: ('referee/keyboard_mouse', RefereeKeyboardMouse, remote_keyboard_mouse),
}
