"""The referee's status commands, decoded by protocol version into SI records.

docs/PROTOCOLS.md §6.2. Layouts changed length between seasons, so a frame is decoded by
(cmd_id, data length) within the configured :class:`ProtocolVersion`; a known command
whose length fits no layout of that version is dropped and counted, never read into the
wrong fields.
"""

from __future__ import annotations

import enum
import math
import struct
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from rm_base.hardware.errors import ProtocolError
from rm_base.hardware.protocols.referee.frame import REMOTE_FRAME_ID, RawFrame
from rm_base.hardware.protocols.referee.remote import decode_remote_payload


class ProtocolVersion(enum.Enum):
    """Referee protocol generations (the season's serial protocol appendix)."""

    V2024 = '2024'  # V1.6.x
    V2025 = '2025'  # V1.7.0 / V1.9.0: chassis power no longer reported
    V2026 = '2026'  # V1.x (13-byte robot status) and V2.0.0 (17 bytes), told apart by length


class Cmd(enum.IntEnum):
    """Referee command ids the robot reads."""

    GAME_STATUS = 0x0001
    ROBOT_STATUS = 0x0201
    POWER_HEAT = 0x0202
    ROBOT_POSITION = 0x0203
    HURT = 0x0206
    SHOOT = 0x0207
    PROJECTILE_ALLOWANCE = 0x0208
    INTERACTION = 0x0301
    KEYBOARD_MOUSE = 0x0304


class GameProgress(enum.IntEnum):
    """Stage of the match (0x0001 bits 4-7)."""

    NOT_STARTED = 0
    PREPARATION = 1
    SELF_CHECK = 2
    COUNTDOWN = 3
    IN_MATCH = 4
    SETTLING = 5


@dataclass(frozen=True)
class GameStatus:
    """0x0001: game type (1 RMUC, 2 RMUT, 3 RMUA, 4 RMUL 3v3, 5 RMUL infantry), stage."""

    game_type: int
    progress: int  # a GameProgress value (others kept as sent)
    stage_remaining_s: int
    unix_time: int


@dataclass(frozen=True)
class RobotStatus:
    """0x0201: who the robot is and the limits the referee sets for it.

    Attributes:
        robot_id: 1 hero, 2 engineer, 3-5 infantry, 6 aerial, 7 sentry...; blue = red + 100.
        barrel_cooling_per_s: heat the barrel loses per second.
        barrel_heat_limit: the heat the barrel may reach.
        chassis_power_limit_w: [W].
        gimbal_power, chassis_power, shooter_power: 24 V on at that output.
        bullet_speed_limit_mps: [m/s], only in the 2026 V2.0.0 layout (None before).
    """

    robot_id: int
    level: int
    hp: int
    max_hp: int
    barrel_cooling_per_s: int
    barrel_heat_limit: int
    chassis_power_limit_w: float
    gimbal_power: bool
    chassis_power: bool
    shooter_power: bool
    bullet_speed_limit_mps: float | None = None

    @property
    def is_blue(self) -> bool:
        """Blue robots have ids above 100."""
        return self.robot_id > 100


@dataclass(frozen=True)
class PowerHeat:
    """0x0202: buffer energy and barrel heat; chassis electrics only up to 2024.

    Attributes:
        chassis_voltage_v, chassis_current_a, chassis_power_w: None from 2025 on (the
            referee no longer reports them).
        buffer_energy_j: [J].
        heat_17mm: barrel heat of the (first) 17 mm launcher.
        heat_17mm_2: the second 17 mm launcher; None in 2026 (one 17 mm heat only).
        heat_42mm: the 42 mm launcher.
    """

    buffer_energy_j: float
    heat_17mm: int
    heat_42mm: int
    heat_17mm_2: int | None = None
    chassis_voltage_v: float | None = None
    chassis_current_a: float | None = None
    chassis_power_w: float | None = None


@dataclass(frozen=True)
class RobotPosition:
    """0x0203: field position [m] and the heading [rad] (0 = north, clockwise as sent)."""

    x_m: float
    y_m: float
    heading_rad: float


@dataclass(frozen=True)
class Hurt:
    """0x0206: which armour (or speed module) took the hurt, and why.

    Causes: 0 hit, 1 offline, 2 over speed, 3 over heat, 4 over chassis power, 5 collision
    (2026 keeps 0, 1 and 5).
    """

    armor_id: int
    cause: int


@dataclass(frozen=True)
class ShootData:
    """0x0207, sent after every projectile.

    Calibre (1 17 mm, 2 42 mm), launcher, firing rate [Hz], muzzle speed [m/s].
    """

    bullet_type: int
    launcher_id: int
    frequency_hz: int
    speed_mps: float


@dataclass(frozen=True)
class ProjectileAllowance:
    """0x0208: projectiles the robot may still fire, and the team's gold."""

    allowance_17mm: int
    allowance_42mm: int
    gold: int
    fortress_17mm: int | None = None  # from V1.9.0 (2025-07) on


@dataclass(frozen=True)
class KeyboardMouse:
    """0x0304 (image link, up to 2026 V1.1.0): the operator's mouse and keyboard.

    Mouse speeds as sent (x negative = left); keys in the DBUS bit order
    (:class:`rm_base.hardware.protocols.dbus.Key`).
    """

    mouse_x: int
    mouse_y: int
    mouse_wheel: int
    left: bool
    right: bool
    keys: int


def _game_status(data: bytes) -> GameStatus:
    head, remaining, unix_time = struct.unpack('<BHQ', data)
    return GameStatus(head & 0x0F, head >> 4, remaining, unix_time)


def _robot_status(data: bytes) -> RobotStatus:
    robot_id, level, hp, max_hp, cooling, heat_limit, power = struct.unpack_from('<BBHHHHH', data)
    speed_limit = None
    if len(data) == 17:  # 2026 V2.0.0: a float speed limit before the output byte
        (speed_limit,) = struct.unpack_from('<f', data, 12)
    outputs = data[-1]
    return RobotStatus(
        robot_id, level, hp, max_hp, cooling, heat_limit, float(power),
        bool(outputs & 1), bool(outputs & 2), bool(outputs & 4), speed_limit,
    )


def _power_heat_2024(data: bytes) -> PowerHeat:
    volts_mv, amps_ma, power, buffer, heat1, heat2, heat42 = struct.unpack('<HHfHHHH', data)
    return PowerHeat(
        float(buffer), heat1, heat42, heat2, volts_mv / 1000.0, amps_ma / 1000.0, power
    )


def _power_heat_2025(data: bytes) -> PowerHeat:
    buffer, heat1, heat2, heat42 = struct.unpack_from('<HHHH', data, 8)
    return PowerHeat(float(buffer), heat1, heat42, heat2)


def _power_heat_2026(data: bytes) -> PowerHeat:
    buffer, heat17, heat42 = struct.unpack_from('<HHH', data, 8)
    return PowerHeat(float(buffer), heat17, heat42)


def _position(data: bytes) -> RobotPosition:
    x, y, angle_deg = struct.unpack('<fff', data)
    return RobotPosition(x, y, math.radians(angle_deg))


def _hurt(data: bytes) -> Hurt:
    return Hurt(data[0] & 0x0F, data[0] >> 4)


def _shoot(data: bytes) -> ShootData:
    bullet_type, launcher, frequency, speed = struct.unpack('<BBBf', data)
    return ShootData(bullet_type, launcher, frequency, speed)


def _allowance(data: bytes) -> ProjectileAllowance:
    values = struct.unpack(f'<{len(data) // 2}H', data)
    return ProjectileAllowance(*values)


def _keyboard_mouse(data: bytes) -> KeyboardMouse:
    x, y, wheel, left, right, keys, _ = struct.unpack('<hhhBBHH', data)
    return KeyboardMouse(x, y, wheel, bool(left), bool(right), keys)


Decoder = Callable[[bytes], Any]

_COMMON: dict[int, dict[int, Decoder]] = {
    Cmd.GAME_STATUS: {11: _game_status},
    Cmd.ROBOT_STATUS: {13: _robot_status},
    Cmd.ROBOT_POSITION: {12: _position},
    Cmd.HURT: {1: _hurt},
    Cmd.SHOOT: {7: _shoot},
    Cmd.KEYBOARD_MOUSE: {12: _keyboard_mouse},
}

#: Per version: cmd_id -> {data length: decoder}.
LAYOUTS: Mapping[ProtocolVersion, Mapping[int, Mapping[int, Decoder]]] = {
    ProtocolVersion.V2024: {
        **_COMMON,
        Cmd.POWER_HEAT: {16: _power_heat_2024},
        Cmd.PROJECTILE_ALLOWANCE: {6: _allowance},
    },
    ProtocolVersion.V2025: {
        **_COMMON,
        Cmd.POWER_HEAT: {16: _power_heat_2025},
        Cmd.PROJECTILE_ALLOWANCE: {6: _allowance, 8: _allowance},
    },
    ProtocolVersion.V2026: {
        **_COMMON,
        Cmd.ROBOT_STATUS: {13: _robot_status, 17: _robot_status},
        Cmd.POWER_HEAT: {14: _power_heat_2026},
        Cmd.PROJECTILE_ALLOWANCE: {8: _allowance},
    },
}


@dataclass
class StatusDecoder:
    """Decodes frames of one protocol version; counts what it cannot decode.

    Attributes:
        version: the protocol the referee speaks.
        decoded: frames decoded, per cmd_id.
        wrong_length: known commands dropped for a length no layout of the version has,
            per (cmd_id, length).
        ignored: frames of commands this decoder does not read, per cmd_id.
        rejected: frames of the right length whose values are impossible (a remote frame
            with a stick out of range), per cmd_id.
    """

    version: ProtocolVersion
    decoded: Counter[int] = field(default_factory=Counter)
    wrong_length: Counter[tuple[int, int]] = field(default_factory=Counter)
    ignored: Counter[int] = field(default_factory=Counter)
    rejected: Counter[int] = field(default_factory=Counter)

    def decode(self, frame: RawFrame) -> Any:
        """The record of frame (GameStatus, RobotStatus, ... RemoteFrame), or None."""
        if frame.cmd_id == REMOTE_FRAME_ID:
            try:
                remote = decode_remote_payload(frame.data)
            except ProtocolError:
                self.rejected[frame.cmd_id] += 1
                return None
            self.decoded[frame.cmd_id] += 1
            return remote
        layouts = LAYOUTS[self.version].get(frame.cmd_id)
        if layouts is None:
            self.ignored[frame.cmd_id] += 1
            return None
        decoder = layouts.get(len(frame.data))
        if decoder is None:
            self.wrong_length[(frame.cmd_id, len(frame.data))] += 1
            return None
        self.decoded[frame.cmd_id] += 1
        return decoder(frame.data)

