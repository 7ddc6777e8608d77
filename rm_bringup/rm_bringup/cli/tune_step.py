"""``rmcli tune step``: a step on one joint, recorded, plotted and measured.

    rmcli tune step yaw 0.5 --from 0           # yaw: hold 0 rad, then step to 0.5 rad
    rmcli tune step yaw 0.5 --from 0 --kp 30   # the same with position_pid.kp 30, this run only

The joint's plugin must be PASSIVE (its PluginState names the joints it drives and their
limits; a target beyond them is refused). For the run it is disabled, so that it does not
turn the joint off under the step, and enabled again after, PASSIVE. The step goes to
can_bridge as /actuator_cmd, the joint's own loop closing it at 1 kHz: MODE_POSITION for a
joint with a position loop, MODE_VELOCITY otherwise (``--loop``). ``--kp/--ki/--kd`` set
that loop's gains (``joints.<joint>.<loop>_pid.*``, live parameters) for the run and put
the old ones back after. The response comes from /joint_states; the figures
(rm_base.control.step_response) are printed, the target and response plotted to
``<output>.png`` and written to ``<output>.csv``. The joint is left limp (MODE_OFF).
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rm_base.control.step_response import StepError, StepFigures, step_figures
from rm_base.sim.socket_bus import INTERFACE_NAME as SIM_INTERFACE

from .errors import CliError
from .options import finite_float, positive_float
from .ros_node import DISCOVERY_TIMEOUT_S, cli_node
from .sim_slip import SlipWatch

_PUBLISH_PERIOD_S = 0.005  # commands well inside the bridge's command_timeout_s (0.1 s)
_PLUGIN_STATE = 'rm_msgs/msg/PluginState'
_GAINS = ('kp', 'ki', 'kd')


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``tune step``."""
    parser.add_argument('joint', help='joint name, as in the robot config (e.g. yaw)')
    parser.add_argument('target', type=finite_float,
                        help='where to step to: position [rad] (or velocity [rad/s])')
    parser.add_argument('--from', dest='start', type=finite_float, default=None,
                        help='hold here first (default: where the joint is)')
    parser.add_argument('--loop', choices=('position', 'velocity'), default=None,
                        help="the joint's loop to step (default: position if it has one)")
    for gain in _GAINS:
        parser.add_argument(f'--{gain}', type=finite_float, default=None,
                            help=f"that loop's {gain} for this run only")
    parser.add_argument('--hold', type=positive_float, default=1.0,
                        help='seconds at the start before the step (default: 1)')
    parser.add_argument('--duration', type=positive_float, default=1.5,
                        help='seconds recorded after the step (default: 1.5)')
    parser.add_argument('-o', '--output', default=None,
                        help='file name without suffix for the .png and .csv '
                        '(default: step_<joint>)')
    parser.add_argument('--bridge', default='/can_bridge', help='the CAN bridge node')
    parser.add_argument('--timeout', type=positive_float, default=DISCOVERY_TIMEOUT_S * 2,
                        help='longest wait for the robot to be found [s]')


@dataclass(frozen=True)
class Owner:
    """The plugin that drives the joint: its node, name and the joint's limits [rad]."""

    node_name: str
    plugin: str
    low: float
    high: float


@dataclass
class Record:
    """The run: when the step went out [ns, node clock], once it has."""

    step_ns: int | None = None


def run(args: argparse.Namespace) -> int:
    """Run the step; print the figures; write the plot and the samples."""
    with cli_node('tune') as node:
        from rclpy.executors import SingleThreadedExecutor

        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        try:
            return _run(args, node, executor)
        finally:
            executor.shutdown()


def _run(args: argparse.Namespace, node: Any, executor: Any) -> int:
    deadline = time.monotonic() + args.timeout
    bridge = _Params(node, executor, args.bridge, deadline)
    joint = args.joint
    if bridge.get(f'joints.{joint}.type') is None:
        raise CliError(f'{args.bridge} has no joint {joint!r}')
    loop = args.loop or ('position' if bridge.get(f'joints.{joint}.position_pid.kp')
                         is not None else 'velocity')
    prefix = f'joints.{joint}.{loop}_pid.'
    old = {g: bridge.get(prefix + g) for g in _GAINS}
    if old['kp'] is None:
        raise CliError(f'joint {joint!r} has no {loop} loop ({prefix}kp is not set)')
    slips = SlipWatch(node, lambda: executor.spin_once(timeout_sec=0.05))
    owner = _owner(node, executor, joint, deadline)
    response = _Response(node, executor, joint, loop, deadline)
    start = args.start if args.start is not None else response.now()
    _check_limits(owner, joint, loop, {'target': args.target} | (
        {'--from': args.start} if args.start is not None else {}), bridge)
    new = {g: getattr(args, g) for g in _GAINS if getattr(args, g) is not None}
    gains = {**old, **new}
    slipped_before = slips.start(_simulated(node, bridge, joint))
    print(f'step {joint} {loop} {start:+.3f} -> {args.target:+.3f} '
          f"({', '.join(f'{g} {gains[g]:g}' for g in _GAINS)}), "
          f'owner {owner.plugin if owner else "none"}', flush=True)
    record = Record()
    if new:
        bridge.set({prefix + g: v for g, v in new.items()})
    try:
        if owner is not None:
            _enable(node, executor, owner, False, time.monotonic() + args.timeout)
        try:
            response.record = record
            drive = _Drive(node, executor, joint, loop)
            drive.hold(start, args.hold)
            record.step_ns = drive.hold(args.target, args.duration)
        finally:
            _Drive(node, executor, joint, 'off').hold(0.0, 0.05)
            response.record = None
            if owner is not None:
                _enable(node, executor, owner, True, time.monotonic() + args.timeout)
    finally:
        if new:
            bridge.set({prefix + g: old[g] for g in new})
    t, y = response.after(record)
    try:
        figures = step_figures(t, y, args.target)
    except StepError as err:
        raise CliError(f'no step response to measure: {err}') from None
    unit = 'rad' if loop == 'position' else 'rad/s'
    print(format_figures(figures, unit))
    slipped = slips.since(slipped_before)
    if slipped:  # the figures are on the wall clock, the joint on the simulated one
        print(f'rmcli: warning: the simulated world slipped {slipped:.2f} s behind the wall '
              'clock during the step (CPU starved): these figures ran slow',
              file=sys.stderr, flush=True)
    out = Path(args.output or f'step_{joint}')
    _write(out, t, y, args.target)
    _plot(out.with_suffix('.png'), t, y, start, args.target, figures=figures,
          title=f'{joint} {loop} step, ' + ', '.join(f'{g} {gains[g]:g}' for g in _GAINS),
          unit=unit)
    print(f'plot: {out.with_suffix(".png")}  samples: {out.with_suffix(".csv")}')
    return 0


def format_figures(f: StepFigures, unit: str) -> str:
    """The four figures, one per line."""
    def seconds(value: float | None, missing: str) -> str:
        return f'{value:.3f} s' if value is not None else missing

    return '\n'.join((
        f'rise time (10-90 %)    {seconds(f.rise_time, "not reached 90 %")}',
        f'overshoot              {f.overshoot_pct:.1f} %',
        f'settling time (2 %)    {seconds(f.settling_time, "not settled")}',
        f'steady-state error     {f.steady_state_error:+.4f} {unit}',
    ))


class _Params:
    """Get and set another node's parameters (its standard services)."""

    def __init__(self, node: Any, executor: Any, name: str, deadline: float) -> None:
        from rclpy.parameter_client import AsyncParameterClient

        self._client = AsyncParameterClient(node, name)
        self._executor, self._name = executor, name
        while not self._client.services_are_ready():
            if time.monotonic() > deadline:
                raise CliError(f'node not found: {name}')
            executor.spin_once(timeout_sec=0.05)

    def _wait(self, future: Any) -> Any:
        end = time.monotonic() + 10.0
        while not future.done() and time.monotonic() < end:
            self._executor.spin_once(timeout_sec=0.05)
        if not future.done():
            raise CliError(f'node {self._name} did not answer in 10 s')
        return future.result()

    def get(self, key: str) -> Any:
        from rclpy.parameter import parameter_value_to_python

        value = self._wait(self._client.get_parameters([key])).values[0]
        return None if value.type == 0 else parameter_value_to_python(value)

    def set(self, values: dict[str, float]) -> None:
        from rclpy.parameter import Parameter

        results = self._wait(self._client.set_parameters(
            [Parameter(k, value=float(v)) for k, v in values.items()])).results
        refused = [r.reason for r in results if not r.successful]
        if refused:
            raise CliError(f'{self._name} refused the gains: {refused[0]}')


def _owner(node: Any, executor: Any, joint: str, deadline: float) -> Owner | None:
    """The plugin that drives joint (from its PluginState), or None if none does.

    Discovery shows a node's topics one by one, so the first state topic only names the
    host node; its ``plugins`` parameter says which states to wait for.
    """
    from rm_base.plugin.base import STATE_QOS

    from rm_msgs.msg import PluginState

    hosts: set[str] = set()
    while not hosts and time.monotonic() < deadline:  # rm_robot, if it runs, shows up
        # /rm_robot/gimbal/state -> /rm_robot
        hosts = {n.rsplit('/', 2)[0] for n, types in node.get_topic_names_and_types()
                 if _PLUGIN_STATE in types}
        executor.spin_once(timeout_sec=0.05)
    topics = [f'{host}/{plugin}/state' for host in sorted(hosts)
              for plugin in _Params(node, executor, host, deadline).get('plugins') or ()]
    states: dict[str, Any] = {}
    subs = [node.create_subscription(PluginState, topic,
                                     lambda msg, topic=topic: states.__setitem__(topic, msg),
                                     STATE_QOS) for topic in topics]
    while len(states) < len(topics) and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    for sub in subs:
        node.destroy_subscription(sub)
    if len(states) < len(topics):
        missing = ', '.join(sorted(set(topics) - set(states)))
        raise CliError(f'no state from {missing}: cannot tell who drives {joint!r}')
    for topic, state in sorted(states.items()):
        if joint in state.joints:
            if state.state_name != 'PASSIVE' and state.enabled:
                raise CliError(
                    f'joint {joint!r} is driven by plugin {state.plugin!r}, now '
                    f'{state.state_name}: command it PASSIVE first')
            i = list(state.joints).index(joint)
            return Owner(topic.rsplit('/', 2)[0], state.plugin, state.joint_min[i],
                         state.joint_max[i])
    return None


def _check_limits(owner: Owner | None, joint: str, loop: str, values: dict[str, float],
                  bridge: _Params) -> None:
    """Refuse a value (by its name: target, --from) beyond the joint's limits."""
    if loop == 'position':
        low, high = (owner.low, owner.high) if owner is not None else (-math.inf, math.inf)
        whose = f" (plugin '{owner.plugin}')" if owner is not None else ''
    else:
        top = bridge.get(f'joints.{joint}.max_velocity')
        low, high = (-top, top) if top is not None else (-math.inf, math.inf)
        whose = ' (its max_velocity)'
    for what, value in values.items():
        if not low <= value <= high:
            raise CliError(f"{what} {value:g} is outside {joint}'s limits "
                           f'[{low:g}, {high:g}]{whose}')


def _enable(node: Any, executor: Any, owner: Owner, on: bool, deadline: float) -> None:
    from std_srvs.srv import SetBool

    name = f'{owner.node_name}/{owner.plugin}/enable'
    client = node.create_client(SetBool, name)
    try:
        while not client.service_is_ready():
            if time.monotonic() > deadline:
                raise CliError(f'service {name} not found')
            executor.spin_once(timeout_sec=0.05)
        future = client.call_async(SetBool.Request(data=on))
        while not future.done() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        if not future.done() or not future.result().success:
            raise CliError(f'{name} {"enable" if on else "disable"} failed')
    finally:
        node.destroy_client(client)


class _Response:
    """The joint's position or velocity from /joint_states, stamped."""

    def __init__(self, node: Any, executor: Any, joint: str, loop: str, deadline: float) -> None:
        from sensor_msgs.msg import JointState

        self._executor, self._joint = executor, joint
        self._field = loop
        self.latest: float | None = None
        self.record: Record | None = None
        self._samples: list[tuple[int, float]] = []
        self._sub = node.create_subscription(JointState, '/joint_states', self._on_state, 50)
        while self.latest is None and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        if self.latest is None:
            raise CliError(f'no /joint_states with joint {joint!r}')

    def _on_state(self, msg: Any) -> None:
        try:
            i = list(msg.name).index(self._joint)
            value = float(getattr(msg, self._field)[i])
        except (ValueError, IndexError):
            return
        self.latest = value
        if self.record is not None:
            stamp = msg.header.stamp
            self._samples.append((stamp.sec * 1_000_000_000 + stamp.nanosec, value))

    def now(self) -> float:
        assert self.latest is not None
        return self.latest

    def after(self, record: Record) -> tuple[list[float], list[float]]:
        """The samples from the step on: t [s] from the step, values."""
        if record.step_ns is None:
            return [], []
        after = [(ns, v) for ns, v in self._samples if ns >= record.step_ns]
        return [(ns - record.step_ns) / 1e9 for ns, _ in after], [v for _, v in after]


class _Drive:
    """/actuator_cmd for one joint, a hand-written command (no states stamp)."""

    def __init__(self, node: Any, executor: Any, joint: str, loop: str) -> None:
        from rm_msgs.msg import ActuatorCmd

        self._node, self._executor, self._joint = node, executor, joint
        self._mode = {'position': ActuatorCmd.MODE_POSITION,
                      'velocity': ActuatorCmd.MODE_VELOCITY, 'off': ActuatorCmd.MODE_OFF}[loop]
        self._loop = loop
        self._pub = node.create_publisher(ActuatorCmd, '/actuator_cmd', 10)

    def hold(self, value: float, seconds: float) -> int:
        """Command value for seconds; return the stamp [ns] of the first command."""
        from rm_msgs.msg import ActuatorCmd

        first = None
        end = time.monotonic() + seconds
        next_send = time.monotonic()
        while time.monotonic() < end:
            if time.monotonic() >= next_send:
                msg = ActuatorCmd(name=[self._joint], mode=[self._mode],
                                  position=[value if self._loop == 'position' else 0.0],
                                  velocity=[value if self._loop == 'velocity' else 0.0],
                                  effort=[0.0], kp=[0.0], kd=[0.0])
                now = self._node.get_clock().now()
                msg.header.stamp = now.to_msg()
                self._pub.publish(msg)
                first = now.nanoseconds if first is None else first
                next_send += _PUBLISH_PERIOD_S
            self._executor.spin_once(timeout_sec=max(0.0, next_send - time.monotonic()))
        assert first is not None
        return first


def _simulated(node: Any, bridge: _Params, joint: str) -> bool:
    """Whether the joint's motor is simulated, so a slip report is worth waiting for.

    The world runs in the bridge (its ``sim`` parameter) or in rm_sim, reached through the
    joint's bus (interface ``rm_sim_socket``) or, with ``--sim-can``, through a kernel
    interface: then only rm_sim's node says so, and discovery may not have brought it yet.
    """
    if bridge.get('sim'):
        return True
    bus = bridge.get(f'joints.{joint}.bus')
    if bus is not None and bridge.get(f'buses.{bus}.interface') == SIM_INTERFACE:
        return True
    return 'rm_sim' in node.get_node_names()


def _write(out: Path, t: list[float], y: list[float], target: float) -> None:
    with open(out.with_suffix('.csv'), 'w', newline='', encoding='utf-8') as f:
        writer = csv.writer(f)
        writer.writerow(['t_s', 'target', 'response'])
        writer.writerows((f'{ti:.6f}', target, f'{yi:.6f}') for ti, yi in zip(t, y, strict=True))


def _plot(path: Path, t: list[float], y: list[float], start: float, target: float, *,
          figures: StepFigures, title: str, unit: str) -> None:
    import matplotlib

    matplotlib.use('Agg')  # files only; no display needed
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 4.5), layout='constrained')
    ax = fig.subplots()
    end = t[-1] if t else 1.0
    ax.step([-0.05 * end, 0.0, end], [start, target, target], where='post', label='target')
    ax.plot(t, y, label='response')
    ax.set_xlabel('time since the step [s]')
    ax.set_ylabel(f'[{unit}]')
    ax.grid(True, alpha=0.3)
    ax.legend(loc='lower right')
    lines = (' '.join(line.split()) for line in format_figures(figures, unit).splitlines())
    fig.suptitle(f'{title}\n' + '; '.join(lines), fontsize='small')
    fig.savefig(path, dpi=100)
