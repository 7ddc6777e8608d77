"""can_bridge parameters -> the CanHardware config dict, the simulator and node settings.

ROS parameters are flat, dotted names: a params YAML's nested keys joined with ``.``
(``joints: {yaw: {velocity_pid: {kp: 0.5}}}`` is ``joints.yaw.velocity_pid.kp``). The
hardware keys are exactly the schema of :mod:`rm_base.hardware.config`; this module nests
them back into the dict :class:`~rm_base.hardware.CanHardware` takes, and lets that
schema's own validation name any bad key (its names are the parameter names).

The node declares its flat parameters (``publish_rate``, ``scheduler.*``, ``safety.*``,
``sim``, ``sim.timing``...) with descriptors; the open groups below are read here. Every
key, with type, unit, bounds and default, is in docs/PARAMETERS.md, generated from the
declarations and the schemas named here:

==============================  =============================================================
``buses.<bus>.*``               a bus: ``hardware.config.BUS_SCHEMA``
``joints.<joint>.*``            a joint: ``hardware.config.JOINT_SCHEMA`` and its family's
                                options
``supercap.*``                  the super-capacitor controller:
                                ``hardware.supercap.SUPERCAP_SCHEMA``
``joints.<joint>.sim.*``        simulated-motor overrides (sim only):
                                ``sim.device_config.MOTOR_SCHEMA``, ``PHYSICS_SCHEMA`` and
                                the family's ``SimFamily.schema``
``sim.body.*``                  robot body: ``sim.body_config.BODY_TABLES``
``sim.imu.*``                   one IMU: ``sim.imu.IMU_SCHEMA``
``sim.referee.*``               the referee system: ``sim.referee.REFEREE_SCHEMA``
``sim.target.*``                a spinning robot to shoot at: ``sim.target.TARGET_SCHEMA``
``sim.supercap.*``              the super-capacitor board (with ``supercap.*``):
                                ``sim.supercap.SUPERCAP_SIM_SCHEMA`` but its channel
``sim.remote.*``                the DR16 receiver: ``sim.operator_link.link_schema``
``sim.image_link.*``            the image link's keyboard/mouse: the same
==============================  =============================================================

With ``sim: false`` the ``sim.*`` groups are ignored, so one robot config serves both.
In a params file ``sim`` and its group cannot both be YAML keys named ``sim`` (rcl reads
a key written twice wrongly); write the group's keys as dotted names::

    can_bridge:
      ros__parameters:
        sim: true
        sim.timing: realtime
        sim.body:
          chassis: {type: mecanum, motors: [wheel_fl, wheel_fr, wheel_rl, wheel_rr], ...}
          gimbal: {yaw: {motor: yaw}, pitch: {motor: pitch}}
        sim.imu: {path: '/tmp/rm_sim_${ROS_DOMAIN_ID}/imu', mount: gimbal}
        joints:
          yaw: {type: gm6020, bus: can0, id: 1, sim: {load_inertia: 0.02}}
"""

from __future__ import annotations

import array
import dataclasses
from collections.abc import Mapping
from pathlib import PurePath
from types import MappingProxyType
from typing import Any

from rm_base.bridge.errors import BridgeConfigError
from rm_base.hardware.config import SAFETY_SCHEMA, HardwareConfig
from rm_base.runtime import cpu_latency
from rm_base.runtime.realtime import EDGE_PRIORITY, LOOP_PRIORITY, choose_cpu
from rm_base.sim import Timing

#: Parameters every rclpy node has; never part of the bridge config.
ROS_OWN_PARAMETERS = frozenset({'use_sim_time', 'start_type_description_service'})
ROS_OWN_PREFIXES = ('qos_overrides.',)

#: Prefixes of the open-ended parameter groups (names chosen by the robot config).
HARDWARE_PREFIXES = ('buses.', 'joints.', 'supercap.')
SIM_BODY_PREFIX = 'sim.body.'
SIM_IMU_PREFIX = 'sim.imu.'
SIM_REFEREE_PREFIX = 'sim.referee.'
SIM_SUPERCAP_PREFIX = 'sim.supercap.'
SIM_TARGET_PREFIX = 'sim.target.'
SIM_REMOTE_PREFIX = 'sim.remote.'
SIM_IMAGE_LINK_PREFIX = 'sim.image_link.'
_JOINT_SIM_KEY = 'sim'
#: ``sim.can``: the simulator's own channels, in the bridge's process.
SIM_CAN_DEFAULT = 'rm_sim'


@dataclasses.dataclass(frozen=True)
class SimSettings:
    """What the bridge needs to build its simulated world.

    Attributes:
        timing: who drives the world's clock.
        seed: random seed of the world.
        can: where the simulated motors answer: ``rm_sim`` (the world's own channels, in
            the process), or a python-can interface (``socketcan``: the kernel's
            interfaces named as the buses' channels, vcan0 ...) that the robot's buses
            open too.
        body: ``body`` of the world config (nested; empty for none).
        imu: the one IMU's config, or None.
        referee: the simulated referee's config, or None.
        target: the spinning robot to shoot at, or None.
        supercap: the simulated super-capacitor board's settings (nested; empty: the
            defaults, if the hardware has a supercap).
        remote: the simulated DR16 receiver's config, or None.
        image_link: the simulated image link's config, or None.
        motors: per joint, overrides of its simulated motor (nested).
    """

    timing: Timing = Timing.REALTIME
    seed: int = 0
    can: str = SIM_CAN_DEFAULT
    body: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    imu: Mapping[str, Any] | None = None
    referee: Mapping[str, Any] | None = None
    remote: Mapping[str, Any] | None = None
    image_link: Mapping[str, Any] | None = None
    supercap: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    target: Mapping[str, Any] | None = None
    motors: Mapping[str, Mapping[str, Any]] = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class BridgeSettings:
    """Everything the node is built from.

    Attributes:
        hardware: the nested CanHardware config dict (validated); in sim mode every bus
            has ``interface: rm_sim`` but no world yet (see :func:`with_sim_world`).
        hardware_config: the same, parsed.
        publish_rate_hz: joint/actuator state rate [Hz].
        diagnostics_rate_hz: /diagnostics rate [Hz].
        publish_frames: publish every CAN frame on ``~/frames``.
        sim: simulator settings, or None on real hardware.
        edge_priority: SCHED_FIFO priority the executable gives the process's other
            threads (:func:`rm_base.runtime.realtime.raise_edge_priority`); 0: none.
        cpu_index: the CPU the executable keeps every Python thread of the process on,
            an index into the CPUs it may use (:func:`rm_base.runtime.realtime.keep_on_cpu`);
            None: wherever the kernel puts them.
        cpu_latency_us: the wake-up latency the executable asks of idle CPUs
            (:func:`rm_base.runtime.realtime.hold_cpu_latency`) [µs]; None: no request.
        calibration_max_speed: a joint turning faster is not at rest (set_zero) [rad/s].
    """

    hardware: Mapping[str, Any]
    hardware_config: HardwareConfig
    publish_rate_hz: float = 200.0
    diagnostics_rate_hz: float = 1.0
    publish_frames: bool = False
    sim: SimSettings | None = None
    edge_priority: int = EDGE_PRIORITY
    cpu_index: int | None = -1
    cpu_latency_us: int | None = 0
    calibration_max_speed: float = 0.05


def plain(value: Any) -> Any:
    """A parameter value as plain Python: arrays (``array.array``, tuples) become lists."""
    if isinstance(value, array.array | tuple):
        return list(value)
    return value


def is_ros_own(name: str) -> bool:
    """True for parameters rclpy declares on every node (not bridge config)."""
    return name in ROS_OWN_PARAMETERS or name.startswith(ROS_OWN_PREFIXES)


def nest(flat: Mapping[str, Any]) -> dict[str, Any]:
    """Turn dotted names into nested dicts: ``{'a.b': 1, 'a.c': 2}`` -> ``{'a': {'b': 1, 'c': 2}}``.

    Raises:
        BridgeConfigError: a name has an empty part, or a name has both a value and
            keys below it (``joints.yaw`` and ``joints.yaw.id``).
    """
    root: dict[str, Any] = {}
    # Sorted, a name comes before the names below it, so a conflict is always seen.
    for name in sorted(flat):
        parts = name.split('.')
        if not all(parts):
            raise BridgeConfigError(f'parameter {name!r} has an empty name part')
        node = root
        for depth, part in enumerate(parts[:-1]):
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                owner = '.'.join(parts[: depth + 1])
                raise BridgeConfigError(
                    f'parameter {name!r} is below {owner!r}, which has a value itself; '
                    f'{owner!r} must be a group of keys'
                )
            node = child
        node[parts[-1]] = plain(flat[name])
    return root


def bus_log_path(path: str, bus: str, several: bool) -> str:
    """The log file of one bus: ``path`` itself, or ``<stem>_<bus><suffix>`` with several."""
    if not several:
        return path
    p = PurePath(path)
    return str(p.with_name(f'{p.stem}_{bus}{p.suffix}'))


def settings_from_parameters(
    typed: Mapping[str, Any], open_params: Mapping[str, Any]
) -> BridgeSettings:
    """Build the bridge settings from its parameters.

    Args:
        typed: the declared, already type-checked parameters: ``publish_rate``,
            ``diagnostics_rate``, ``publish_frames``, ``log_file``, ``sim``,
            ``sim.timing`` (:class:`Timing` or its value), ``sim.seed``, ``sim.can``,
            ``scheduler.rate_hz``, ``scheduler.receive_in_loop``, ``scheduler.priority``,
            ``scheduler.edge_priority``, ``scheduler.one_cpu``, ``scheduler.cpu``,
            ``scheduler.cpu_latency_us``,
            ``scheduler.collect_garbage``,
            ``calibration.max_speed`` and ``safety.*``;
            missing ones take their defaults.
        open_params: every other parameter by its flat name (rclpy's own excluded).

    Returns:
        The settings, with a validated hardware config.

    Raises:
        BridgeConfigError: an unknown parameter or a nesting conflict.
        HardwareConfigError: the hardware schema refuses a key (the message names it).
    """
    hardware_flat: dict[str, Any] = {}
    motors_flat: dict[str, dict[str, Any]] = {}
    body_flat: dict[str, Any] = {}
    imu_flat: dict[str, Any] = {}
    referee_flat: dict[str, Any] = {}
    supercap_flat: dict[str, Any] = {}
    target_flat: dict[str, Any] = {}
    remote_flat: dict[str, Any] = {}
    image_link_flat: dict[str, Any] = {}
    for name, value in open_params.items():
        if name.startswith(HARDWARE_PREFIXES):
            parts = name.split('.')
            if parts[0] == 'joints' and len(parts) > 2 and parts[2] == _JOINT_SIM_KEY:
                if len(parts) == 3:
                    raise BridgeConfigError(
                        f'parameter {name!r} must be a group of simulated-motor keys '
                        f'({name}.load_inertia, ...)'
                    )
                motors_flat.setdefault(parts[1], {})['.'.join(parts[3:])] = value
            else:
                hardware_flat[name] = value
        elif name.startswith(SIM_BODY_PREFIX):
            body_flat[name.removeprefix(SIM_BODY_PREFIX)] = value
        elif name.startswith(SIM_IMU_PREFIX):
            imu_flat[name.removeprefix(SIM_IMU_PREFIX)] = value
        elif name.startswith(SIM_REFEREE_PREFIX):
            referee_flat[name.removeprefix(SIM_REFEREE_PREFIX)] = value
        elif name.startswith(SIM_SUPERCAP_PREFIX):
            supercap_flat[name.removeprefix(SIM_SUPERCAP_PREFIX)] = value
        elif name.startswith(SIM_TARGET_PREFIX):
            target_flat[name.removeprefix(SIM_TARGET_PREFIX)] = value
        elif name.startswith(SIM_REMOTE_PREFIX):
            remote_flat[name.removeprefix(SIM_REMOTE_PREFIX)] = value
        elif name.startswith(SIM_IMAGE_LINK_PREFIX):
            image_link_flat[name.removeprefix(SIM_IMAGE_LINK_PREFIX)] = value
        else:
            raise BridgeConfigError(
                f'unknown parameter {name!r}; the bridge takes buses.*, joints.*, supercap.*, '
                'scheduler.rate_hz, scheduler.receive_in_loop, scheduler.(edge_)priority, '
                'scheduler.collect_garbage, safety.*, '
                'publish_rate, '
                'diagnostics_rate, publish_frames, log_file, sim, sim.timing, sim.seed, sim.can, '
                'sim.body.*, sim.imu.*, sim.referee.*, sim.supercap.*, sim.target.*, '
                'sim.remote.*, sim.image_link.*'
            )
    hardware = nest(hardware_flat)
    sim_on = bool(typed.get('sim', False))
    sim_can = str(typed.get('sim.can', SIM_CAN_DEFAULT)) or SIM_CAN_DEFAULT
    buses = hardware.get('buses')
    if isinstance(buses, dict):
        log_file = typed.get('log_file') or None
        for bus_name, bus in buses.items():
            if not isinstance(bus, dict):
                continue  # the hardware schema reports it, naming the key
            if sim_on:
                # Same code path as on a robot; only the python-can interface differs.
                bus['interface'] = sim_can
            if log_file and 'log_file' not in bus:
                bus['log_file'] = bus_log_path(log_file, bus_name, len(buses) > 1)
    scheduler = {
        'rate_hz': typed.get('scheduler.rate_hz', 1000.0),
        'receive_in_loop': typed.get('scheduler.receive_in_loop', True),
        'priority': typed.get('scheduler.priority', LOOP_PRIORITY),
        'collect_garbage': typed.get('scheduler.collect_garbage', True),
    }
    safety = {
        key: typed[f'safety.{key}']
        for key in sorted(SAFETY_SCHEMA.names)
        if f'safety.{key}' in typed
    }
    hardware['scheduler'] = scheduler
    hardware['safety'] = safety
    hardware_config = HardwareConfig.from_dict(hardware)
    sim = None
    if sim_on:
        unknown_motors = sorted(set(motors_flat) - {j.name for j in hardware_config.joints})
        if unknown_motors:
            raise BridgeConfigError(
                f'joints.{unknown_motors[0]}.sim.* is set, but joints.{unknown_motors[0]} '
                'is not a configured joint (its type, bus or id is missing)'
            )
        sim = SimSettings(
            timing=Timing(typed.get('sim.timing', Timing.REALTIME)),
            seed=int(typed.get('sim.seed', 0)),
            can=sim_can,
            body=nest(body_flat),
            imu=nest(imu_flat) if imu_flat else None,
            referee=nest(referee_flat) if referee_flat else None,
            supercap=nest(supercap_flat),
            target=nest(target_flat) if target_flat else None,
            remote=nest(remote_flat) if remote_flat else None,
            image_link=nest(image_link_flat) if image_link_flat else None,
            motors={joint: nest(keys) for joint, keys in motors_flat.items()},
        )
    return BridgeSettings(
        hardware=MappingProxyType(hardware),
        hardware_config=hardware_config,
        publish_rate_hz=float(typed.get('publish_rate', 200.0)),
        diagnostics_rate_hz=float(typed.get('diagnostics_rate', 1.0)),
        publish_frames=bool(typed.get('publish_frames', False)),
        sim=sim,
        edge_priority=int(typed.get('scheduler.edge_priority', EDGE_PRIORITY)),
        cpu_index=cpu_index(typed),
        cpu_latency_us=cpu_latency.from_parameter(int(typed.get('scheduler.cpu_latency_us', 0))),
        calibration_max_speed=float(typed.get('calibration.max_speed', 0.05)),
    )


def cpu_index(typed: Mapping[str, Any]) -> int | None:
    """``scheduler.cpu`` if ``scheduler.one_cpu``, checked against this machine's CPUs.

    Raises:
        BridgeConfigError: the index is outside the CPUs the process may use.
    """
    if not typed.get('scheduler.one_cpu', True):
        return None
    index = int(typed.get('scheduler.cpu', -1))
    try:
        choose_cpu(index)
    except ValueError as err:
        raise BridgeConfigError(f'scheduler.cpu: {err}') from err
    return index


def with_sim_world(hardware: Mapping[str, Any], world: Any) -> dict[str, Any]:
    """A copy of the hardware config whose every ``rm_sim`` bus opens on ``world``.

    The world goes in ``options.world``; a bus on another interface (``sim.can``) is left
    as it is.

    Passing the world object (not its config) makes every bus share it, and keeps it
    alive when a bus is closed and reopened after an error.
    """
    config = dict(hardware)
    config['buses'] = {
        name: {**bus, 'options': {**bus.get('options', {}), 'world': world}}
        if bus.get('interface') == SIM_CAN_DEFAULT else bus
        for name, bus in hardware['buses'].items()
    }
    return config
