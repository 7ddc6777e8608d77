"""Configuration of the CAN hardware layer, built from plain dicts (YAML, ROS parameters).

The schema, with units (every key optional unless marked *required*)::

    {
      'buses': {                       # *required*, one entry per CAN bus
        'can0': {
          'interface': 'socketcan',    # *required*: any python-can interface
                                       # (socketcan, gs_usb, slcan, pcan, virtual, rm_sim...)
          'channel': 'can0',           # default: the bus name
          'bitrate': 1000000,          # [bit/s]; also used for the bus-load estimate
          'fd': False,                 # CAN FD
          'data_bitrate': None,        # [bit/s], CAN FD data phase
          'options': {},               # extra keyword arguments for can.Bus(...)
          'log_file': None,            # python-can log (.asc/.blf/.log/.csv/.trc/.txt)
          'send_timeout_s': 0.001,     # [s] timeout of one send
          'receive_timeout_s': 0.05,   # [s] how long the receive thread blocks per call
          'reconnect_initial_s': 0.05, # [s] first reopen delay after an error
          'reconnect_max_s': 2.0,      # [s] cap of the exponential back-off
          'send_failures_to_reopen': 20,   # consecutive failed sends that mean "bus gone"
        },
      },
      'joints': {                      # *required*: name -> joint (or a list with 'name')
        'yaw': {
          'type': 'gm6020',            # *required*: see rm_base.motors.joint_types()
          'bus': 'can0',               # *required*
          'id': 1,                     # *required*: ESC / motor / joint id
          'direction': 1,              # +1 or -1: sign between motor and joint
          'gear_ratio': None,          # motor turns per joint turn (type default)
          'zero_offset': 0.0,          # [rad] output-shaft angle that is joint zero
          'max_effort': None,          # [N·m] output clamp (type default)
          'max_velocity': None,        # [rad/s] velocity target clamp (type default)
          'torque_constant': None,     # [N·m/A] at the joint (type default)
          'temperature_limit': None,   # [°C] above it the joint is held at zero
          'velocity_pid': {'kp': ..., 'ki': ..., 'kd': ..., ...},   # rad/s -> N·m
          'position_pid': {'kp': ..., ...},                          # rad -> rad/s
          ...                          # family options (model, limits, master_id...)
        },
      },
      'scheduler': {'rate_hz': 1000.0,
                    'receive_in_loop': True},  # feedback taken by the loop, no rx threads
      'safety': {
        'feedback_timeout_s': 0.1,     # no feedback this long -> offline, zero output
        'command_timeout_s': 0.1,      # no command this long -> zero output
        'temperature_hysteresis_c': 5.0,   # resume below limit - hysteresis
      },
    }

PID sub-dicts take the fields of :class:`rm_base.control.PidGains` (``kp``, ``ki``, ``kd``,
``output_limit``, ``integral_limit``, ``integral_separation``, ``deadband``,
``derivative_tau_s``), or with ``form: incremental`` those of the incremental PID with a
tracking differentiator (:mod:`rm_base.control.pid_form`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

from rm_base.control import PidConfig, PidGains, pid_config
from rm_base.errors import ConfigError
from rm_base.hardware.errors import HardwareConfigError

_EMPTY: Mapping[str, Any] = MappingProxyType({})


def _check_keys(where: str, data: Mapping[str, Any], allowed: set[str]) -> None:
    unknown = set(data) - allowed
    if unknown:
        raise HardwareConfigError(
            f'{where}: unknown key(s) {sorted(unknown)}; allowed: {sorted(allowed)}'
        )


def _number(where: str, value: Any, *, positive: bool = False, allow_none: bool = False) -> Any:
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise HardwareConfigError(f'{where} must be a finite number, got {value!r}')
    if positive and value <= 0:
        raise HardwareConfigError(f'{where} must be > 0, got {value!r}')
    return float(value)


def _integer(where: str, value: Any, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise HardwareConfigError(f'{where} must be an integer in {low}..{high}, got {value!r}')
    return value


def _mapping(where: str, value: Any) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise HardwareConfigError(f'{where} must be a mapping, got {type(value).__name__}')
    return value


def pid_gains(where: str, data: Any) -> PidConfig:
    """A loop's PID config from a dict (``form``: positional or incremental).

    The error names ``where``.

    Raises:
        HardwareConfigError: not a mapping, unknown form or field, or an invalid value.
    """
    if data is None:
        return PidGains()
    data = _mapping(where, data)
    try:
        return pid_config(data)
    except (ConfigError, TypeError) as err:
        raise HardwareConfigError(f'{where}: {err}') from err


@dataclasses.dataclass(frozen=True)
class BusConfig:
    """One CAN bus (see the module docstring for the keys and units)."""

    name: str
    interface: str
    channel: Any
    bitrate: int | None = 1_000_000
    fd: bool = False
    data_bitrate: int | None = None
    options: Mapping[str, Any] = dataclasses.field(default_factory=lambda: _EMPTY)
    log_file: str | None = None
    send_timeout_s: float = 0.001
    receive_timeout_s: float = 0.05
    reconnect_initial_s: float = 0.05
    reconnect_max_s: float = 2.0
    send_failures_to_reopen: int = 20

    @classmethod
    def from_dict(cls, name: str, data: Mapping[str, Any]) -> BusConfig:
        """Parse one entry of ``buses``.

        Raises:
            HardwareConfigError: a missing, unknown or invalid key.
        """
        where = f'buses.{name}'
        data = _mapping(where, data)
        _check_keys(where, data, {f.name for f in dataclasses.fields(cls)} - {'name'})
        interface = data.get('interface')
        if not isinstance(interface, str) or not interface:
            raise HardwareConfigError(f'{where}.interface is required (e.g. socketcan, rm_sim)')
        bitrate = data.get('bitrate', 1_000_000)
        if bitrate is not None:
            bitrate = _integer(f'{where}.bitrate', bitrate, 1, 10_000_000)
        data_bitrate = data.get('data_bitrate')
        if data_bitrate is not None:
            data_bitrate = _integer(f'{where}.data_bitrate', data_bitrate, 1, 20_000_000)
        log_file = data.get('log_file')
        if log_file is not None and not isinstance(log_file, str):
            raise HardwareConfigError(f'{where}.log_file must be a path string, got {log_file!r}')
        initial = _number(
            f'{where}.reconnect_initial_s', data.get('reconnect_initial_s', 0.05), positive=True
        )
        maximum = _number(
            f'{where}.reconnect_max_s', data.get('reconnect_max_s', 2.0), positive=True
        )
        if maximum < initial:
            raise HardwareConfigError(f'{where}.reconnect_max_s must be >= reconnect_initial_s')
        return cls(
            name=name,
            interface=interface,
            channel=data.get('channel', name),
            bitrate=bitrate,
            fd=bool(data.get('fd', False)),
            data_bitrate=data_bitrate,
            options=MappingProxyType(dict(_mapping(f'{where}.options', data.get('options', {})))),
            log_file=log_file,
            send_timeout_s=_number(
                f'{where}.send_timeout_s', data.get('send_timeout_s', 0.001), positive=True
            ),
            receive_timeout_s=_number(
                f'{where}.receive_timeout_s', data.get('receive_timeout_s', 0.05), positive=True
            ),
            reconnect_initial_s=initial,
            reconnect_max_s=maximum,
            send_failures_to_reopen=_integer(
                f'{where}.send_failures_to_reopen',
                data.get('send_failures_to_reopen', 20),
                1,
                1_000_000,
            ),
        )


#: Keys every joint understands; the rest go to the family as ``options``.
COMMON_JOINT_KEYS = frozenset(
    {
        'name',
        'type',
        'bus',
        'id',
        'direction',
        'gear_ratio',
        'zero_offset',
        'max_effort',
        'max_velocity',
        'torque_constant',
        'temperature_limit',
        'velocity_pid',
        'position_pid',
    }
)


@dataclasses.dataclass(frozen=True)
class JointConfig:
    """One joint. None means "the type's default" (see the actuator family).

    Attributes:
        name: joint name, as in ActuatorCmd/ActuatorState.
        type: actuator type name (``m3508``, ``gm6020``, ``dm4310``...).
        bus: bus name.
        id: ESC / motor / joint id.
        direction: +1 or -1.
        gear_ratio: motor turns per joint turn.
        zero_offset: output-shaft angle that is joint zero [rad].
        max_effort: output clamp [N·m].
        max_velocity: velocity target clamp [rad/s].
        torque_constant: [N·m/A] at the joint.
        temperature_limit: [°C].
        velocity_pid: velocity loop, rad/s -> N·m.
        position_pid: position loop, rad -> rad/s.
        options: family-specific keys, validated by the family.
    """

    name: str
    type: str
    bus: str
    id: int
    direction: int = 1
    gear_ratio: float | None = None
    zero_offset: float = 0.0
    max_effort: float | None = None
    max_velocity: float | None = None
    torque_constant: float | None = None
    temperature_limit: float | None = None
    velocity_pid: PidConfig = dataclasses.field(default_factory=PidGains)
    position_pid: PidConfig = dataclasses.field(default_factory=PidGains)
    options: Mapping[str, Any] = dataclasses.field(default_factory=lambda: _EMPTY)

    @classmethod
    def from_dict(cls, name: str, data: Mapping[str, Any]) -> JointConfig:
        """Parse one joint entry.

        Raises:
            HardwareConfigError: a missing or invalid key.
        """
        where = f'joints.{name}'
        data = _mapping(where, data)
        for key in ('type', 'bus'):
            if not isinstance(data.get(key), str) or not data.get(key):
                raise HardwareConfigError(f'{where}.{key} is required and must be a string')
        if 'id' not in data:
            raise HardwareConfigError(f'{where}.id is required')
        direction = data.get('direction', 1)
        if direction not in (1, -1) or isinstance(direction, bool):
            raise HardwareConfigError(f'{where}.direction must be +1 or -1, got {direction!r}')
        gear = _number(f'{where}.gear_ratio', data.get('gear_ratio'), allow_none=True)
        if gear is not None and gear <= 0:
            raise HardwareConfigError(
                f'{where}.gear_ratio must be > 0 (use direction for the sign), got {gear}'
            )
        optional_positive = {}
        for key in ('max_effort', 'max_velocity', 'torque_constant'):
            value = _number(f'{where}.{key}', data.get(key), allow_none=True)
            if value is not None and value <= 0:
                raise HardwareConfigError(f'{where}.{key} must be > 0, got {value}')
            optional_positive[key] = value
        return cls(
            name=name,
            type=data['type'].lower(),
            bus=data['bus'],
            id=_integer(f'{where}.id', data['id'], 0, 0x1FFFFFFF),
            direction=int(direction),
            gear_ratio=gear,
            zero_offset=_number(f'{where}.zero_offset', data.get('zero_offset', 0.0)),
            temperature_limit=_number(
                f'{where}.temperature_limit', data.get('temperature_limit'), allow_none=True
            ),
            velocity_pid=pid_gains(f'{where}.velocity_pid', data.get('velocity_pid')),
            position_pid=pid_gains(f'{where}.position_pid', data.get('position_pid')),
            options=MappingProxyType({k: v for k, v in data.items() if k not in COMMON_JOINT_KEYS}),
            **optional_positive,
        )


@dataclasses.dataclass(frozen=True)
class SafetyConfig:
    """Safety rules every joint follows, independent of any plugin.

    Attributes:
        feedback_timeout_s: no feedback this long -> offline, output zero [s].
        command_timeout_s: no command this long -> output zero [s].
        temperature_hysteresis_c: after over-temperature, resume below
            ``temperature_limit - hysteresis`` [°C].
    """

    feedback_timeout_s: float = 0.1
    command_timeout_s: float = 0.1
    temperature_hysteresis_c: float = 5.0

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None) -> SafetyConfig:
        """Parse ``safety``.

        Raises:
            HardwareConfigError: unknown or invalid key.
        """
        data = _mapping('safety', data or {})
        _check_keys('safety', data, {f.name for f in dataclasses.fields(cls)})
        return cls(
            **{
                k: _number(f'safety.{k}', v, positive=k != 'temperature_hysteresis_c')
                for k, v in data.items()
            }
        )


@dataclasses.dataclass(frozen=True)
class HardwareConfig:
    """Everything :class:`rm_base.hardware.CanHardware` is built from."""

    buses: tuple[BusConfig, ...]
    joints: tuple[JointConfig, ...]
    rate_hz: float = 1000.0
    safety: SafetyConfig = SafetyConfig()
    receive_in_loop: bool = True
    priority: int = 0

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> HardwareConfig:
        """Parse the whole config dict (schema in the module docstring).

        Raises:
            HardwareConfigError: anything missing, unknown or invalid, naming where.
        """
        data = _mapping('config', data)
        _check_keys('config', data, {'buses', 'joints', 'scheduler', 'safety'})
        buses_data = _mapping('buses', data.get('buses'))
        if not buses_data:
            raise HardwareConfigError('buses: at least one bus is required')
        buses = tuple(BusConfig.from_dict(str(n), d) for n, d in buses_data.items())
        joints_data = data.get('joints')
        if isinstance(joints_data, Mapping):
            items = [(str(n), d) for n, d in joints_data.items()]
        elif isinstance(joints_data, list | tuple):
            items = []
            for i, d in enumerate(joints_data):
                if not isinstance(d, Mapping) or not isinstance(d.get('name'), str):
                    raise HardwareConfigError(f'joints[{i}] needs a string "name"')
                items.append((d['name'], d))
        else:
            raise HardwareConfigError('joints is required: a mapping name -> joint, or a list')
        names = [n for n, _ in items]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise HardwareConfigError(f'joints: duplicate name(s) {duplicates}')
        joints = tuple(JointConfig.from_dict(n, d) for n, d in items)
        bus_names = {b.name for b in buses}
        for j in joints:
            if j.bus not in bus_names:
                raise HardwareConfigError(
                    f'joints.{j.name}.bus {j.bus!r} is not a configured bus {sorted(bus_names)}'
                )
        scheduler = _mapping('scheduler', data.get('scheduler') or {})
        _check_keys('scheduler', scheduler, {'rate_hz', 'receive_in_loop', 'priority'})
        rate = _number('scheduler.rate_hz', scheduler.get('rate_hz', 1000.0), positive=True)
        if rate > 10_000:
            raise HardwareConfigError(f'scheduler.rate_hz {rate} above 10000 Hz')
        in_loop = scheduler.get('receive_in_loop', True)
        if not isinstance(in_loop, bool):
            raise HardwareConfigError(
                f'scheduler.receive_in_loop must be true or false, got {in_loop!r}'
            )
        priority = scheduler.get('priority', 0)
        if isinstance(priority, bool) or not isinstance(priority, int) or not 0 <= priority <= 99:
            raise HardwareConfigError(
                f'scheduler.priority must be an integer 0-99 (0: normal scheduling), '
                f'got {priority!r}'
            )
        safety = SafetyConfig.from_dict(data.get('safety'))
        return cls(buses, joints, rate, safety, in_loop, priority)
