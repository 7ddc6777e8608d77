"""Configuration of the CAN hardware layer, built from plain dicts (YAML, ROS parameters).

The config is ``{'buses': {name: bus}, 'joints': {name: joint} (or a list of joints with a
'name'), 'scheduler': {...}, 'safety': {...}, 'supercap': {...}}`` (``supercap`` optional:
``rm_base.hardware.supercap.SUPERCAP_SCHEMA``). Each table's keys, with type, unit, bounds,
default and description, are declared once below (``BUS_SCHEMA``, ``JOINT_SCHEMA``,
``SCHEDULER_SCHEMA``, ``SAFETY_SCHEMA``); the same declarations validate a config (errors
name the key) and give the tables of docs/PARAMETERS.md. A joint's keys beyond
``JOINT_SCHEMA`` are its motor family's options, checked by the family.

PID sub-dicts take the fields of :class:`rm_base.control.PidGains` (``kp``, ``ki``, ``kd``,
``output_limit``, ``integral_limit``, ``integral_separation``, ``deadband``,
``derivative_tau_s``), or with ``form: incremental`` those of the incremental PID with a
tracking differentiator (:mod:`rm_base.control.pid_form`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

from rm_base.config.schema import Key, Schema, boolean, integer, mapping, number, one_of, string
from rm_base.control import PidConfig, PidGains, pid_config
from rm_base.errors import ConfigError
from rm_base.hardware.errors import HardwareConfigError
from rm_base.hardware.supercap import SupercapConfig, check_bus

_EMPTY: Mapping[str, Any] = MappingProxyType({})


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


#: ``buses.<bus>``: one CAN bus.
BUS_SCHEMA = Schema((
    string('interface', nonempty=True, description='python-can interface: socketcan on a robot, '
           'rm_sim_socket on the simulator (gs_usb, slcan, pcan, virtual... work too)'),
    Key('channel', 'any', lambda v: v, 'the interface channel (can0, a USB serial...); '
        'default: the bus name', default=None),
    integer('bitrate', 1_000_000, unit='bit/s', ge=1, le=10_000_000,
            description='bus bitrate; also used for the bus-load estimate'),
    boolean('fd', False, description='CAN FD'),
    integer('data_bitrate', None, unit='bit/s', ge=1, le=20_000_000,
            description='CAN FD data-phase bitrate'),
    mapping('options', {}, description='extra keyword arguments of can.Bus(...)'),
    string('log_file', None, description='python-can log of this bus (.asc/.blf/.log/...)'),
    number('send_timeout_s', 0.001, unit='s', gt=0.0, description='timeout of one send'),
    number('receive_timeout_s', 0.05, unit='s', gt=0.0,
           description='how long a receive thread blocks per call'),
    number('reconnect_initial_s', 0.05, unit='s', gt=0.0,
           description='first reopen delay after an error'),
    number('reconnect_max_s', 2.0, unit='s', gt=0.0,
           description='cap of the exponential reopen back-off (>= reconnect_initial_s)'),
    integer('send_failures_to_reopen', 20, ge=1, le=1_000_000,
            description='consecutive failed sends that mean "bus gone": close and reopen'),
))


@dataclasses.dataclass(frozen=True)
class BusConfig:
    """One CAN bus (keys, units and defaults: ``BUS_SCHEMA``)."""

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
        values = BUS_SCHEMA.read(where, data, HardwareConfigError)
        if values['reconnect_max_s'] < values['reconnect_initial_s']:
            raise HardwareConfigError(f'{where}.reconnect_max_s must be >= reconnect_initial_s')
        if values['channel'] is None:
            values['channel'] = name
        values['options'] = MappingProxyType(values['options'])
        return cls(name=name, **values)


#: ``joints.<joint>``: the keys every joint takes; the rest are its family's options.
JOINT_SCHEMA = Schema(
    (
        string('type', lower=True, nonempty=True,
               description="joint type (m3508, gm6020, dm4310...: 'can_bridge joint types')"),
        string('bus', nonempty=True,
               description='name of the bus (a key of buses) the joint is on'),
        integer('id', ge=0, le=0x1FFFFFFF, description='ESC / motor / joint id on its bus'),
        one_of('direction', (1, -1), 1, description='sign between the motor and the joint'),
        number('gear_ratio', None, gt=0.0,
               description="motor turns per joint turn (> 0: direction gives the sign); "
               "default: the type's"),
        number('zero_offset', 0.0, unit='rad',
               description='output-shaft angle that is the joint zero'),
        number('max_effort', None, unit='N·m', gt=0.0,
               description="output clamp; default: the type's"),
        number('max_velocity', None, unit='rad/s', gt=0.0,
               description="velocity target clamp; default: the type's"),
        number('torque_constant', None, unit='N·m/A', gt=0.0,
               description="torque per ampere at the joint; default: the type's"),
        number('temperature_limit', None, unit='degC',
               description="above it the joint is held at zero; default: the type's"),
        mapping('velocity_pid', None,
                description='velocity loop (rad/s -> N·m): PidGains fields, or form: incremental; '
                "a positional loop's gains and limits may be set while running"),
        mapping('position_pid', None,
                description='position loop (rad -> rad/s): PidGains fields, or form: incremental; '
                "a positional loop's gains and limits may be set while running"),
    ),
    open=True,
)

#: Keys every joint understands; the rest go to the family as ``options``.
COMMON_JOINT_KEYS = JOINT_SCHEMA.names | {'name'}


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
        """Parse one joint entry (keys: ``JOINT_SCHEMA``; the rest are options).

        Raises:
            HardwareConfigError: a missing or invalid key.
        """
        where = f'joints.{name}'
        values = JOINT_SCHEMA.read(where, data, HardwareConfigError)
        for key in ('velocity_pid', 'position_pid'):
            values[key] = pid_gains(f'{where}.{key}', values[key])
        options = {k: v for k, v in JOINT_SCHEMA.extras(data).items() if k != 'name'}
        return cls(name=name, options=MappingProxyType(options), **values)


#: ``safety``: rules every joint follows, whatever the plugins do.
SAFETY_SCHEMA = Schema((
    number('feedback_timeout_s', 0.1, unit='s', gt=0.0,
           description='a joint without feedback this long is offline and held at zero'),
    number('command_timeout_s', 0.1, unit='s', gt=0.0,
           description='a joint without a command this long is held at zero'),
    number('temperature_hysteresis_c', 10.0, unit='degC', ge=0.0,
           description='after over-temperature, resume below temperature_limit minus this'),
    number('fault_clear_s', 1.0, unit='s', ge=0.0, le=60.0,
           description='a latched fault (over-temperature, device fault, implausible feedback, '
                       'offline after having been online) clears only after its condition has '
                       'been gone this long, on consistent feedback'),
    number('max_temperature_step_c', 5.0, unit='degC', gt=0.0,
           description='a temperature that moves more than this between two frames is '
                       'implausible feedback'),
))

#: ``scheduler``: the control loop.
SCHEDULER_SCHEMA = Schema((
    number('rate_hz', 1000.0, unit='Hz', gt=0.0, le=10_000.0, description='control loop rate'),
    boolean('receive_in_loop', True,
            description='the loop takes the received feedback (no receive thread per bus)'),
    integer('priority', 0, ge=0, le=99,
            description='real-time (SCHED_FIFO) priority of the loop thread; 0: normal '
            'scheduling; without the right to it the loop runs on, with a warning'),
    boolean('collect_garbage', True,
            description="the loop runs the interpreter's garbage collection after its "
            'send, never mid-tick (false: CPython collects whenever it allocates)'),
))


@dataclasses.dataclass(frozen=True)
class SafetyConfig:
    """Safety rules every joint follows, independent of any plugin.

    Attributes:
        feedback_timeout_s: no feedback this long -> offline, output zero [s].
        command_timeout_s: no command this long -> output zero [s].
        temperature_hysteresis_c: after over-temperature, resume below
            ``temperature_limit - hysteresis`` [°C].
        fault_clear_s: a latched fault clears only after its condition has been gone this
            long, on consistent feedback [s] (docs/RELIABILITY.md, "Faults latch").
        max_temperature_step_c: a temperature step between two frames beyond this is
            implausible feedback [°C].
    """

    feedback_timeout_s: float = 0.1
    command_timeout_s: float = 0.1
    temperature_hysteresis_c: float = 10.0
    fault_clear_s: float = 1.0
    max_temperature_step_c: float = 5.0

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None) -> SafetyConfig:
        """Parse ``safety``.

        Raises:
            HardwareConfigError: unknown or invalid key.
        """
        return cls(**SAFETY_SCHEMA.read('safety', data or {}, HardwareConfigError))


@dataclasses.dataclass(frozen=True)
class HardwareConfig:
    """Everything :class:`rm_base.hardware.CanHardware` is built from."""

    buses: tuple[BusConfig, ...]
    joints: tuple[JointConfig, ...]
    rate_hz: float = 1000.0
    safety: SafetyConfig = SafetyConfig()
    receive_in_loop: bool = True
    priority: int = 0
    collect_garbage: bool = True
    supercap: SupercapConfig | None = None

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> HardwareConfig:
        """Parse the whole config dict (see the module docstring).

        Raises:
            HardwareConfigError: anything missing, unknown or invalid, naming where.
        """
        data = _mapping('config', data)
        unknown = set(data) - {'buses', 'joints', 'scheduler', 'safety', 'supercap'}
        if unknown:
            raise HardwareConfigError(
                f'config: unknown key(s) {sorted(unknown)}; '
                'allowed: buses, joints, scheduler, safety, supercap'
            )
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
        scheduler = SCHEDULER_SCHEMA.read(
            'scheduler', data.get('scheduler') or {}, HardwareConfigError
        )
        safety = SafetyConfig.from_dict(data.get('safety'))
        supercap = None
        if data.get('supercap') is not None:
            supercap = SupercapConfig.from_dict(_mapping('supercap', data['supercap']))
            check_bus(supercap, bus_names)
        return cls(
            buses, joints, scheduler['rate_hz'], safety, scheduler['receive_in_loop'],
            scheduler['priority'], scheduler['collect_garbage'], supercap,
        )
