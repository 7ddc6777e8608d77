"""The referee's status commands, encoded: the referee's side of :mod:`.status`.

The simulated referee (rm_base.sim.referee) sends these, and tests build frames with them.
Each encoder writes the layout its decoder in :mod:`.status` reads, for the same
:class:`ProtocolVersion` (docs/PROTOCOLS.md §6.2); reserved bytes are zero.
"""

from __future__ import annotations

import math
import struct
from typing import Any

from rm_base.hardware.protocols.referee.status import (
    Cmd,
    GameStatus,
    Hurt,
    KeyboardMouse,
    PowerHeat,
    ProjectileAllowance,
    ProtocolVersion,
    RobotPosition,
    RobotStatus,
    ShootData,
)


def _game_status(r: GameStatus, version: ProtocolVersion) -> bytes:
    return struct.pack('<BHQ', (r.game_type & 0x0F) | (r.progress << 4), r.stage_remaining_s,
                       r.unix_time)


def _robot_status(r: RobotStatus, version: ProtocolVersion) -> bytes:
    head = struct.pack(
        '<BBHHHHH', r.robot_id, r.level, r.hp, r.max_hp, r.barrel_cooling_per_s,
        r.barrel_heat_limit, round(r.chassis_power_limit_w),
    )
    outputs = bytes([int(r.gimbal_power) | int(r.chassis_power) << 1 | int(r.shooter_power) << 2])
    if r.bullet_speed_limit_mps is None:
        return head + outputs
    if version is not ProtocolVersion.V2026:
        raise ValueError(f'a bullet speed limit is only sent in 2026, not {version.value}')
    return head + struct.pack('<f', r.bullet_speed_limit_mps) + outputs


def _power_heat(r: PowerHeat, version: ProtocolVersion) -> bytes:
    buffer = round(r.buffer_energy_j)
    if version is ProtocolVersion.V2026:
        return bytes(8) + struct.pack('<HHH', buffer, r.heat_17mm, r.heat_42mm)
    heat_2 = r.heat_17mm_2 or 0
    if version is ProtocolVersion.V2025:
        return bytes(8) + struct.pack('<HHHH', buffer, r.heat_17mm, heat_2, r.heat_42mm)
    electrics = (r.chassis_voltage_v, r.chassis_current_a, r.chassis_power_w)
    volts, amps, watts = (0.0 if v is None else v for v in electrics)
    return struct.pack(
        '<HHfHHHH', round(volts * 1000.0), round(amps * 1000.0), watts, buffer, r.heat_17mm,
        heat_2, r.heat_42mm,
    )


def _position(r: RobotPosition, version: ProtocolVersion) -> bytes:
    return struct.pack('<fff', r.x_m, r.y_m, math.degrees(r.heading_rad))


def _hurt(r: Hurt, version: ProtocolVersion) -> bytes:
    return bytes([(r.armor_id & 0x0F) | (r.cause << 4)])


def _shoot(r: ShootData, version: ProtocolVersion) -> bytes:
    return struct.pack('<BBBf', r.bullet_type, r.launcher_id, r.frequency_hz, r.speed_mps)


def _allowance(r: ProjectileAllowance, version: ProtocolVersion) -> bytes:
    values = [r.allowance_17mm, r.allowance_42mm, r.gold]
    if version is not ProtocolVersion.V2024:  # V1.9.0 (2025-07) on: the fortress's too
        values.append(r.fortress_17mm or 0)
    return struct.pack(f'<{len(values)}H', *values)


def _keyboard_mouse(r: KeyboardMouse, version: ProtocolVersion) -> bytes:
    return struct.pack('<hhhBBHH', r.mouse_x, r.mouse_y, r.mouse_wheel, int(r.left),
                       int(r.right), r.keys, 0)


_ENCODERS: dict[type, tuple[Cmd, Any]] = {
    GameStatus: (Cmd.GAME_STATUS, _game_status),
    RobotStatus: (Cmd.ROBOT_STATUS, _robot_status),
    PowerHeat: (Cmd.POWER_HEAT, _power_heat),
    RobotPosition: (Cmd.ROBOT_POSITION, _position),
    Hurt: (Cmd.HURT, _hurt),
    ShootData: (Cmd.SHOOT, _shoot),
    ProjectileAllowance: (Cmd.PROJECTILE_ALLOWANCE, _allowance),
    KeyboardMouse: (Cmd.KEYBOARD_MOUSE, _keyboard_mouse),
}


def encode_status(record: Any, version: ProtocolVersion) -> tuple[int, bytes]:
    """The (cmd_id, data) of a status record in the layout of version.

    Raises:
        TypeError: not a status record.
        ValueError: the version has no layout for it (a 2026 speed limit in 2024), or a
            value does not fit its field.
    """
    try:
        cmd, encode = _ENCODERS[type(record)]
    except KeyError:
        raise TypeError(f'not a referee status record: {record!r}') from None
    try:
        return int(cmd), encode(record, version)
    except struct.error as err:
        raise ValueError(f'{record!r} does not fit 0x{cmd:04X}: {err}') from None
