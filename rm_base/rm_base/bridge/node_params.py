"""can_bridge's ROS parameters: declared on its node with descriptors, read into settings.

The flat parameters (``publish_rate``, ``scheduler.*``, ``safety.*``, ``sim``...) are
declared here one by one; the open groups (``buses.*``, ``joints.*``, ``sim.*``) are read
and checked by :mod:`rm_base.bridge.params`, which has no rclpy. Every key, with type,
unit, bounds and default: docs/PARAMETERS.md.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node
from rclpy.parameter import Parameter

from rm_base.bridge.errors import BridgeConfigError
from rm_base.bridge.live_gains import FIELDS as LIVE_FIELDS
from rm_base.bridge.params import (
    SIM_CAN_DEFAULT,
    BridgeSettings,
    is_ros_own,
    plain,
    settings_from_parameters,
)
from rm_base.config.calibration import CalibrationFile, joint_zero_offsets
from rm_base.config.schema import Schema
from rm_base.control import PidGains
from rm_base.hardware.config import SAFETY_SCHEMA, SCHEDULER_SCHEMA
from rm_base.plugin.params import PluginParams
from rm_base.runtime.realtime import EDGE_PRIORITY, LOOP_PRIORITY
from rm_base.sim import Timing


def read_parameters(node: Node) -> tuple[BridgeSettings, CalibrationFile | None]:
    """Declare the bridge's parameters on node and read them.

    Returns:
        The settings, and the calibration file where set_zero keeps the joint zeros
        (None without ``calibration.file``).

    Raises:
        ConfigError: a parameter is missing, unknown or invalid; the message names it.
    """
    _check_sim_group(node)
    params = PluginParams(node, plugin='', prefix='')
    typed: dict[str, Any] = {}

    def fresh(name: str) -> str:
        # Declared from the overrides already (if set): redeclare with a descriptor.
        if node.has_parameter(name):
            node.undeclare_parameter(name)
        return name

    def declare(name: str, read: Callable[..., Any], *args: Any, **kwargs: Any) -> None:
        typed[name] = read(fresh(name), *args, **kwargs)

    def declare_schema(prefix: str, schema: Schema, **defaults: Any) -> None:
        group = params.group(prefix)
        for key in schema.keys:
            if key.name in defaults:
                key = dataclasses.replace(key, default=defaults[key.name])  # noqa: PLW2901
            fresh(group.key(key.name))
            typed[group.key(key.name)] = group.declare_key(key)

    declare(
        'publish_rate',
        params.double,
        200.0,
        unit='Hz',
        gt=0.0,
        le=1000.0,
        description='rate of joint_states and actuator_states',
    )
    declare(
        'diagnostics_rate',
        params.double,
        1.0,
        unit='Hz',
        gt=0.0,
        le=100.0,
        description='rate of /diagnostics',
    )
    declare(
        'publish_frames',
        params.boolean,
        False,
        description='publish every CAN frame sent and received on ~/frames (debugging)',
    )
    declare(
        'log_file',
        params.string,
        '',
        description='python-can log of every frame (.asc/.blf/.log/...); empty: none; '
        'with several buses <stem>_<bus><suffix>',
    )
    # a robot's loop runs at real-time priority
    declare_schema('scheduler', SCHEDULER_SCHEMA, priority=LOOP_PRIORITY)
    declare(
        'scheduler.edge_priority',
        params.integer,
        EDGE_PRIORITY,
        ge=0,
        le=99,
        description="real-time priority the executable gives the process's other "
        'threads, below the loop (a thread holding the GIL must not be preempted); 0: '
        'normal scheduling',
    )
    declare(
        'scheduler.cpu_latency_us',
        params.integer,
        0,
        ge=-1,
        le=1_000_000,
        description='the executable asks the kernel to wake idle CPUs within this many '
        'microseconds while it runs (/dev/cpu_dma_latency; 0: idle CPUs poll); -1: no request',
    )
    declare(
        'scheduler.one_cpu',
        params.boolean,
        True,
        description='the executable runs every Python thread of the process on one CPU '
        '(scheduler.cpu), where the loop keeps the GIL for its whole tick',
    )
    declare(
        'scheduler.cpu',
        params.integer,
        -1,
        description='with scheduler.one_cpu, which CPU: an index into the CPUs the '
        'process may use, -1 the last',
    )
    declare_schema('safety', SAFETY_SCHEMA)
    declare(
        'sim',
        params.boolean,
        False,
        description='run every bus on the simulator rm_sim (world from sim.* and joints)',
    )
    declare(
        'sim.timing',
        params.choice,
        Timing,
        Timing.REALTIME,
        description='realtime: a physics thread; stepped: only sim_world.step() (tests)',
    )
    declare(
        'sim.can',
        params.string,
        SIM_CAN_DEFAULT,
        description="where the simulated motors answer: rm_sim (the simulator's own "
        'channels, in this process) or a python-can interface the buses open too '
        "(socketcan: the kernel's interfaces named as the buses' channels, e.g. vcan0)",
    )
    declare(
        'sim.seed',
        params.integer,
        0,
        ge=0,
        description='random seed of the simulated world (garbage faults)',
    )
    declare(
        'calibration.file',
        params.string,
        '',
        description='calibration file (~ and ${VAR} expanded): joint zeros set by '
        '~/<joint>/set_zero are kept there and replace joints.<joint>.zero_offset at '
        'start-up; empty: zeros last until the node stops',
    )
    declare(
        'calibration.max_speed',
        params.double,
        0.05,
        unit='rad/s',
        gt=0.0,
        description='a joint turning faster is moving: set_zero refuses',
    )
    open_params = {
        name: plain(parameter.value)
        for name, parameter in _parameters_under(node, '').items()
        if name not in typed and not is_ros_own(name)
    }
    calibration = CalibrationFile(typed['calibration.file']) if typed['calibration.file'] else None
    if calibration is not None:
        for joint, zero in joint_zero_offsets(calibration).items():
            if not any(name.startswith(f'joints.{joint}.') for name in open_params):
                node.get_logger().warning(
                    f'{calibration.path} has a zero for joint {joint!r}, which '
                    'this robot does not have: ignored'
                )
                continue
            open_params[f'joints.{joint}.zero_offset'] = zero
            node.get_logger().info(f'{joint}: zero_offset {zero:.6f} rad from {calibration.path}')
    return settings_from_parameters(typed, open_params), calibration


def declare_live_gains(node: Node, loops: Mapping[str, Mapping[str, Any]]) -> None:
    """Declare every live field of each positional PID the config gives, as a double.

    rclpy declared the config's keys from the file, typed as written: ``kp: 20`` an
    integer, which then refused a live ``20.5``, and a field the file left out (``kd``)
    could not be set at all. Each is declared again with its value in use and a descriptor.

    Args:
        node: the bridge's node.
        loops: ``{joint: {loop: PidConfig}}``, as read at start-up.
    """
    given = set(_parameters_under(node, 'joints'))  # 'yaw.position_pid.kp', ...
    for joint, configs in loops.items():
        for loop, gains in configs.items():
            if not isinstance(gains, PidGains) or not any(
                    name.startswith(f'{joint}.{loop}.') for name in given):
                continue  # an incremental loop (read at start-up), or none configured
            for field in sorted(LIVE_FIELDS):
                name = f'joints.{joint}.{loop}.{field}'
                if node.has_parameter(name):
                    node.undeclare_parameter(name)
                node.declare_parameter(name, float(getattr(gains, field)), ParameterDescriptor(
                    name=name, type=Parameter.Type.DOUBLE.value,
                    description=f"joint {joint}'s {loop.replace('_', ' ')}: {field}",
                    additional_constraints='type: double; set while running',
                ), ignore_override=True)


def _parameters_under(node: Node, prefix: str) -> dict[str, Parameter]:
    # rclpy 7.1.6 annotates the values as parameter values; they are Parameter objects
    parameters: dict[str, Any] = node.get_parameters_by_prefix(prefix)
    return parameters


def _check_sim_group(node: Node) -> None:
    # A params file with both `sim: true` and a `sim:` group (one YAML key twice) is
    # read by rcl as no `sim` at all and the `true` moved onto the group's first key.
    if node.has_parameter('sim'):
        return
    for name, parameter in _parameters_under(node, 'sim').items():
        if isinstance(parameter.value, bool):
            raise BridgeConfigError(
                f"parameter 'sim.{name}' is {parameter.value} and 'sim' is missing: the "
                "params file has the key 'sim' twice (sim: true and a sim: group); write "
                "sim: true and the group's keys as dotted names: sim.timing: realtime, "
                'sim.body: {...}, sim.imu: {...}'
            )
