"""The manual-control mapping: switch positions, sticks, keys and mouse -> commands.

Loaded from a YAML file (``default_mapping.yaml`` documents every key and is the
default); every value is checked and a bad one is a :class:`MappingError` naming its key.
Pure: no rclpy.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum
from importlib import resources
from pathlib import Path
from typing import Any

import yaml
from rm_base.errors import ConfigError
from rm_base.hardware.protocols.dbus import Key

from rm_msgs.msg import ChassisCmd, ShootCmd

#: The mapping used when a robot names none.
DEFAULT_MAPPING = 'default_mapping.yaml'


class MappingError(ConfigError):
    """A mapping file that cannot be used; the message names the key."""


class Drive(Enum):
    """Who drives, by the right switch."""

    PASSIVE = 'passive'
    REMOTE = 'remote'
    KEYBOARD = 'keyboard'


@dataclass(frozen=True)
class Stick:
    """One stick channel (0..3) scaled to a command (full stick = scale)."""

    channel: int
    scale: float


@dataclass(frozen=True)
class RemoteMapping:
    """What the sticks and the left switch command."""

    chassis_mode: int
    vx: Stick
    vy: Stick
    yaw_rate: Stick
    pitch_rate: Stick
    shooter: Mapping[str, int]  # left switch position -> ShootCmd mode


@dataclass(frozen=True)
class KeyboardMapping:
    """What the keyboard and the mouse command."""

    chassis_mode: int
    speed: float
    gears: Mapping[int, int]  # key bit -> ChassisCmd.speed_gear while it is held
    mouse_yaw: float
    mouse_pitch: float
    chassis_keys: Mapping[int, int]  # key bit -> ChassisCmd mode
    friction_key: int
    fire: str  # 'left' or 'right'


@dataclass(frozen=True)
class ManualMapping:
    """The whole mapping (see default_mapping.yaml)."""

    right_switch: str  # 'switch_a' or 'switch_b'
    modes: Mapping[str, Drive]  # 'up' | 'mid' | 'down' -> who drives
    remote: RemoteMapping
    keyboard: KeyboardMapping
    shot_speed: float
    shot_hz: float

    @property
    def left_switch(self) -> str:
        """The other switch field."""
        return 'switch_b' if self.right_switch == 'switch_a' else 'switch_a'


_POSITIONS = ('up', 'mid', 'down')


def load_mapping(path: str | Path | None = None) -> ManualMapping:
    """Read and check a mapping file (None or '': the default).

    Raises:
        MappingError: the file cannot be read, or a key is missing, unknown or invalid.
    """
    where = f'manual mapping {path or DEFAULT_MAPPING}'
    try:
        if path:
            text = Path(path).expanduser().read_text(encoding='utf-8')
        else:
            text = resources.files(__package__).joinpath(DEFAULT_MAPPING).read_text('utf-8')
        data = yaml.safe_load(text)
    except (OSError, yaml.YAMLError) as err:
        raise MappingError(f'{where}: {err}') from err
    except UnicodeDecodeError as err:
        raise MappingError(f'{where} is not a text file (byte {err.start} is not UTF-8)') from None
    try:
        return parse_mapping(data)
    except MappingError as err:  # say which file: a robot may name its own
        raise MappingError(f'{where}: {err}') from None


def parse_mapping(data: Any) -> ManualMapping:
    """Check a mapping given as plain data (the YAML file's content)."""
    top = _section(data, '', {'right_switch', 'modes', 'remote', 'keyboard', 'shooter'})
    right = top['right_switch']
    if right not in ('switch_a', 'switch_b'):
        raise MappingError(f'right_switch must be switch_a or switch_b, got {right!r}')
    modes_in = _section(top['modes'], 'modes', set(_POSITIONS))
    modes = {pos: _enum(Drive, modes_in[pos], f'modes.{pos}') for pos in _POSITIONS}
    shooter = _section(top['shooter'], 'shooter', {'speed', 'hz'})
    return ManualMapping(
        right_switch=right,
        modes=modes,
        remote=_remote(top['remote']),
        keyboard=_keyboard(top['keyboard']),
        shot_speed=_number(shooter['speed'], 'shooter.speed', positive=True),
        shot_hz=_number(shooter['hz'], 'shooter.hz', positive=True),
    )


def _remote(data: Any) -> RemoteMapping:
    keys = {'chassis_mode', 'vx', 'vy', 'yaw_rate', 'pitch_rate', 'shooter'}
    section = _section(data, 'remote', keys)
    sticks = {}
    for name in ('vx', 'vy', 'yaw_rate', 'pitch_rate'):
        stick = _section(section[name], f'remote.{name}', {'channel', 'scale'})
        channel = stick['channel']
        if isinstance(channel, bool) or channel not in (0, 1, 2, 3):
            raise MappingError(f'remote.{name}.channel must be 0..3, got {channel!r}')
        sticks[name] = Stick(channel, _number(stick['scale'], f'remote.{name}.scale'))
    shooter = _section(section['shooter'], 'remote.shooter', set(_POSITIONS))
    return RemoteMapping(
        chassis_mode=_mode(ChassisCmd, section['chassis_mode'], 'remote.chassis_mode'),
        shooter={
            pos: _mode(ShootCmd, shooter[pos], f'remote.shooter.{pos}') for pos in _POSITIONS
        },
        **sticks,
    )


def _keyboard(data: Any) -> KeyboardMapping:
    keys = {'chassis_mode', 'speed', 'gears', 'mouse_yaw', 'mouse_pitch', 'chassis_keys',
            'friction_key', 'fire'}
    section = _section(data, 'keyboard', keys)
    gears = _mapping(section['gears'], 'keyboard.gears')
    chassis_keys = _mapping(section['chassis_keys'], 'keyboard.chassis_keys')
    fire = section['fire']
    if fire not in ('left', 'right'):
        raise MappingError(f'keyboard.fire must be left or right, got {fire!r}')
    return KeyboardMapping(
        chassis_mode=_mode(ChassisCmd, section['chassis_mode'], 'keyboard.chassis_mode'),
        speed=_number(section['speed'], 'keyboard.speed', positive=True),
        gears={
            _key(k, 'keyboard.gears'): _gear(v, f'keyboard.gears.{k}') for k, v in gears.items()
        },
        mouse_yaw=_number(section['mouse_yaw'], 'keyboard.mouse_yaw'),
        mouse_pitch=_number(section['mouse_pitch'], 'keyboard.mouse_pitch'),
        chassis_keys={
            _key(k, 'keyboard.chassis_keys'): _mode(ChassisCmd, v, f'keyboard.chassis_keys.{k}')
            for k, v in chassis_keys.items()
        },
        friction_key=_key(section['friction_key'], 'keyboard.friction_key'),
        fire=fire,
    )


# -- checks ----------------------------------------------------------------------------------


def _section(data: Any, where: str, keys: set[str]) -> Mapping[str, Any]:
    name = where or 'the mapping'
    if not isinstance(data, Mapping):
        raise MappingError(f'{name} must be a mapping, got {data!r}')
    unknown = sorted(set(data) - keys)
    if unknown:
        raise MappingError(f'{name}: unknown key(s) {unknown}; known: {sorted(keys)}')
    missing = sorted(keys - set(data))
    if missing:
        prefix = f'{where}.' if where else ''
        raise MappingError(f'missing key(s) {[prefix + k for k in missing]}')
    return data


def _mapping(data: Any, where: str) -> Mapping[str, Any]:
    if not isinstance(data, Mapping):
        raise MappingError(f'{where} must be a mapping, got {data!r}')
    return data


def _number(value: Any, where: str, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise MappingError(f'{where} must be a finite number, got {value!r}')
    if positive and value <= 0.0:
        raise MappingError(f'{where} must be > 0, got {value!r}')
    return float(value)


def _enum(kind: type[Enum], value: Any, where: str) -> Any:
    try:
        return kind(value)
    except ValueError:
        known = ', '.join(str(m.value) for m in kind)
        raise MappingError(f'{where} must be one of {known}, got {value!r}') from None


def _mode(msg_type: type, name: Any, where: str) -> int:
    """A mode constant of the command message by its name (``GYRO``)."""
    value = getattr(msg_type, name, None) if isinstance(name, str) and name.isupper() else None
    if not isinstance(value, int):
        known = [n for n in dir(msg_type) if n.isupper() and isinstance(getattr(msg_type, n), int)]
        raise MappingError(f'{where} must be one of {", ".join(known)}, got {name!r}')
    return value


def _gear(name: Any, where: str) -> int:
    """A ChassisCmd speed gear by its name (``FAST`` for ``GEAR_FAST``)."""
    known = [n.removeprefix('GEAR_') for n in dir(ChassisCmd) if n.startswith('GEAR_')]
    if not isinstance(name, str) or name not in known:
        raise MappingError(f'{where} must be one of {", ".join(known)}, got {name!r}')
    gear: int = getattr(ChassisCmd, f'GEAR_{name}')
    return gear


def _key(name: Any, where: str) -> int:
    if not isinstance(name, str) or name not in Key.__members__:
        raise MappingError(f'{where}: {name!r} is not a key; keys: {", ".join(Key.__members__)}')
    return int(Key[name])
