"""bringup: the whole robot in one process — can_bridge, rm_robot and a live status line.

    bringup --robot standard --sim        # the standard robot on the simulated CAN bus
    bringup --robot hero                  # the hero on its real buses (socketcan)
    bringup --config my_robot.yaml --sim  # any robot config file
    bringup --sim --params-file extra.yaml  # and overrides, after the robot's config
    bringup --sim --sim-time              # every node on /clock (`rmcli bag play --clock`)
    bringup --sim --foxglove              # and the robot live in Foxglove (ws://127.0.0.1:8765)
    bringup --sim --sim-can socketcan     # rm_sim on the kernel's CAN (vcan can0, can1)

The robot config is a ROS parameter file with a ``can_bridge`` and an ``rm_robot``
section (rm_bringup/config/<robot>.yaml). ``--sim`` starts rm_sim, the simulated motors
and IMU, in a process of their own from the config and its simulation overlay
(<robot>_sim.yaml), and runs every bus on it through the ``rm_sim_socket`` interface
(rm_bringup.sim_process); the robot itself runs as it would on socketcan.
The plugins run inside the bridge's 1 kHz CAN loop (one thread: feedback, due plugins,
actuator updates, pack, send), setting joint targets on the actuators directly; both
nodes' ROS callbacks share one EventsExecutor at the edge. On Ctrl-C (or SIGTERM) every
plugin commands zero output first, then the bridge sends zero-current frames, then the
process exits.
"""

from __future__ import annotations

import argparse
import logging
import os
import pathlib
import sys
import tempfile
import time
from typing import Any

import rclpy
import yaml
from rclpy.experimental import EventsExecutor
from rclpy.utilities import remove_ros_args
from rm_base.bridge import CanBridgeNode
from rm_base.bridge.node import NODE_NAME as BRIDGE_NODE_NAME
from rm_base.errors import ConfigError
from rm_base.host.node import RobotHost
from rm_base.ros.env import bounded_teardown
from rm_base.ros.log import forward_package_logging
from rm_base.ros.node_main import init_ros, spin_until_shutdown
from rm_base.runtime.realtime import prepare_loop_process

from rm_bringup.console import Console
from rm_bringup.sim_process import SimProcess
from rm_bringup.status import StatusView, fit_status

#: The node of the operator's commander, when the robot config has a section for it.
MANUAL_NODE_NAME = 'rm_manual'

# How long one spin_once may block [s]; bounds the reaction to Ctrl-C.
_SPIN_TIMEOUT = 0.05
# Status line period [s] on a terminal (rewritten in place) and in a log (one per line).
_TTY_PERIOD = 0.25
_LOG_PERIOD = 2.0


def config_dir() -> pathlib.Path:
    """The installed config folder of rm_bringup (share/rm_bringup/config)."""
    from ament_index_python.packages import get_package_share_directory

    return pathlib.Path(get_package_share_directory('rm_bringup')) / 'config'


def parameter_files(robot: str | None, config: str | None, sim: bool) -> list[pathlib.Path]:
    """The parameter files to load, robot config first, then its simulation overlay.

    Raises:
        ConfigError: the config (or, with sim, its overlay) does not exist.
    """
    if config is not None:
        base = pathlib.Path(config)
    else:
        base = config_dir() / f'{robot}.yaml'
    if not base.is_file():
        known = sorted(p.stem for p in config_dir().glob('*.yaml') if not p.stem.endswith('_sim'))
        raise ConfigError(f'robot config {base} not found; installed robots: {", ".join(known)}')
    files = [base]
    if sim:
        overlay = base.with_name(f'{base.stem}_sim.yaml')
        if not overlay.is_file():
            raise ConfigError(f'--sim needs the simulation overlay {overlay}, which is missing')
        files.append(overlay)
    return files


def parse_args(argv: list[str]) -> argparse.Namespace:
    """Parse the command line (see the module docstring), less any ROS arguments.

    launch_ros may append ``--ros-args ...`` to the command line: those are rclpy's.
    """
    parser = argparse.ArgumentParser(prog='bringup', description=__doc__.split('\n\n')[0])
    which = parser.add_mutually_exclusive_group()
    which.add_argument('--robot', default='standard', help='installed robot config name')
    which.add_argument('--config', help='path of a robot config file (instead of --robot)')
    parser.add_argument('--sim', action='store_true', help='run every bus on rm_sim')
    parser.add_argument(
        '--sim-can', default=None, metavar='INTERFACE',
        help="with --sim: rm_sim answers on this python-can interface's channels named as "
        "the robot's (socketcan: vcan interfaces can0, can1) and the robot's buses stay as "
        'its config has them; default: rm_sim_socket',
    )
    parser.add_argument(
        '--params-file', action='append', default=[], type=pathlib.Path,
        help="another parameter file, after the robot's config (repeatable), e.g. "
        'can_bridge: log_file',
    )
    parser.add_argument(
        '--sim-time', action='store_true',
        help='every node runs on /clock (use_sim_time), e.g. replayed by `rmcli bag play --clock`',
    )
    parser.add_argument(
        '--foxglove', type=int, nargs='?', const=8765, default=None, metavar='PORT',
        help='serve the topics and parameters to Foxglove on ws://127.0.0.1:PORT (8765; 0: '
        'any free port); loopback only',
    )
    parser.add_argument('--no-status', action='store_true', help='no live status line')
    parser.add_argument(
        '--duration', type=float, default=None, help='stop after this many seconds [s]'
    )
    args = parser.parse_args(remove_ros_args(['bringup', *argv])[1:])
    if args.sim_can is not None and not args.sim:
        parser.error('--sim-can needs --sim')
    return args


class _StatusPrinter:
    """Prints the status line: kept at the bottom of a terminal, a line at a time otherwise."""

    def __init__(self, view: StatusView, console: Console | None, stream=sys.stdout) -> None:
        self._view = view
        self._console = console
        self._stream = stream
        self._period = _TTY_PERIOD if console is not None else _LOG_PERIOD
        self._next = time.monotonic() + self._period

    def maybe_print(self) -> None:
        now = time.monotonic()
        if now < self._next:
            return
        self._next = now + self._period
        line = self._view.line()
        if self._console is not None:
            width = os.get_terminal_size(self._stream.fileno()).columns
            self._console.show(fit_status(line, max(width - 1, 20)))
        else:
            self._stream.write(line + '\n')
            self._stream.flush()


def main(argv: list[str] | None = None) -> int:
    """Run the robot until Ctrl-C/SIGTERM (or --duration); return the exit status."""
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        files = parameter_files(args.robot, args.config, args.sim)
    except ConfigError as err:
        print(f'[bringup] {err}', file=sys.stderr)
        return 1
    # On a terminal the status line stays at the bottom and log lines scroll above it; set
    # up first, so that rm_sim's lines go above it too.
    console = Console() if not args.no_status and sys.stdout.isatty() else None
    try:
        return _main(args, files, console)
    finally:
        if console is not None:
            console.close()


def _main(args: argparse.Namespace, files: list[pathlib.Path], console: Console | None) -> int:
    with tempfile.TemporaryDirectory(prefix='rm_bringup_') as workdir:
        sim = None
        if args.sim:
            try:
                # the extra files too: they may add devices or change the simulated ones
                sim = SimProcess([*files, *args.params_file], pathlib.Path(workdir),
                                 args.sim_can)
            except ConfigError as err:
                print(f'[bringup] {err}', file=sys.stderr)
                return 1
        try:
            node_files = [*files, *args.params_file]
            if sim is not None:  # this run's rm_sim socket, after a dump of an earlier run's
                node_files.append(sim.bridge_overlay)
            ros_args = ['--ros-args']
            for path in node_files:
                ros_args += ['--params-file', str(path)]
            if args.sim_time:  # after the files: it wins over a config's own use_sim_time
                ros_args += ['-p', 'use_sim_time:=true']
            if not init_ros('bringup', ['bringup', *ros_args]):
                return 1
            # the hardware layer's log lines (offline joints, bus errors) under the
            # bridge's name
            handler = forward_package_logging(BRIDGE_NODE_NAME)
            try:
                return _run(args, files, console)
            finally:
                logging.getLogger('rm_base').removeHandler(handler)
        finally:
            if sim is not None:
                sim.stop()  # after the bridge's zero frames


def duplicated(names: list[str], ours: list[str]) -> list[str]:
    """Our node names that the graph holds more than once (another robot's), sorted."""
    return sorted(n for n in set(ours) if names.count(n) > 1)


class _SecondRobotGuard:
    """Says, once per change, that another robot runs in the same ROS domain.

    Its topics and services mix with ours (a fault service may land on its rm_sim). It is
    checked every few seconds, discovery being what it is, and said as an error.
    """

    PERIOD_S = 3.0

    def __init__(self, node: Any, ours: list[str]) -> None:
        self._node, self._ours = node, ours
        self._next = time.monotonic() + self.PERIOD_S
        self._said: list[str] = []

    def check(self) -> None:
        now = time.monotonic()
        if now < self._next:
            return
        self._next = now + self.PERIOD_S
        twice = duplicated(self._node.get_node_names(), self._ours)
        if twice and twice != self._said:
            domain = os.environ.get('ROS_DOMAIN_ID', '0')
            self._node.get_logger().error(
                f'another robot runs in ROS domain {domain}: {", ".join(twice)} twice; its '
                "topics and services mix with this one's. Stop it, or give each robot its "
                'own ROS_DOMAIN_ID')
        self._said = twice


def has_section(files: list[pathlib.Path], node: str) -> bool:
    """Whether a parameter file has a section for node (``rm_manual:``)."""
    for path in files:
        with open(path) as stream:
            if node in (yaml.safe_load(stream) or {}):
                return True
    return False


def _start_view(executor: Any, nodes: list[Any], host: RobotHost, port: int) -> Any:
    """The Foxglove view of the robot, its node spun by executor; says where it listens."""
    from rm_bringup.foxglove_view import NODE_NAME, FoxgloveView
    from rm_bringup.robot_description import describe_host

    node = rclpy.create_node(NODE_NAME)
    executor.add_node(node)
    try:
        view = FoxgloveView(node, nodes, description=describe_host(host), port=port)
    except RuntimeError as err:  # the port given is taken: the robot runs on, unseen
        print(f'[bringup] no Foxglove view: {err}', file=sys.stderr)
        return None
    print(f'[bringup] Foxglove: ws://127.0.0.1:{view.port} (Foxglove app: Open connection)',
          flush=True)
    return view


def _run(args: argparse.Namespace, files: list[pathlib.Path], console: Console | None) -> int:
    bridge = host = manual = None
    try:
        bridge = CanBridgeNode()
        host = RobotHost(hardware=bridge.hardware)
        # The operator's commander is a node of its own, so the plugins hear it over DDS
        # beside any other commander (docs/ARCHITECTURE.md, "Manual control").
        if has_section(files, MANUAL_NODE_NAME):
            manual = RobotHost(node_name=MANUAL_NODE_NAME)
    except (ConfigError, KeyboardInterrupt) as err:
        for node in (manual, host, bridge):
            if node is not None:
                node.destroy_node()
        rclpy.try_shutdown()
        if isinstance(err, KeyboardInterrupt):
            return 0
        print(f'[bringup] configuration error: {err}', file=sys.stderr)
        return 1

    # One EventsExecutor for both nodes' callbacks (the ROS edge): 4x cheaper per message
    # than the SingleThreadedExecutor (docs/ROS_FROM_WHEELS.md); its spin() ignores
    # SIGINT, so spin_once.
    executor = EventsExecutor()
    executor.add_node(bridge)
    executor.add_node(host)
    if manual is not None:
        executor.add_node(manual)
    prepare_loop_process(bridge.edge_priority, bridge.cpu_index, bridge.cpu_latency_us)
    printer = None if args.no_status else _StatusPrinter(StatusView(host), console)
    deadline = None if args.duration is None else time.monotonic() + args.duration
    mode = 'on rm_sim' if args.sim else 'on its CAN buses'
    print(f'[bringup] {", ".join(p.name for p in files)}: robot running {mode}; Ctrl-C stops')

    ours = [n.get_name() for n in (bridge, host, manual) if n is not None]
    guard = _SecondRobotGuard(bridge, ours + (['rm_sim'] if args.sim else []))

    def tick() -> bool:
        if printer is not None:
            printer.maybe_print()
        guard.check()
        return deadline is None or time.monotonic() < deadline

    view = None
    try:
        if args.foxglove is not None:  # in the try: a failure still stops the robot cleanly
            view = _start_view(executor, [n for n in (bridge, host, manual) if n is not None],
                               host, args.foxglove)
        spin_until_shutdown(executor, on_tick=tick, timeout_sec=_SPIN_TIMEOUT)
    finally:
        if view is not None:
            view.close()
        # Plugins first (zero targets on their joints), then the bridge's zero frames.
        if manual is not None:
            manual.shutdown()
        host.shutdown()
        bridge.shutdown()
        with bounded_teardown():
            executor.shutdown()
            for node in (manual, host, bridge):
                if node is not None:
                    node.destroy_node()
            rclpy.try_shutdown()
        print('[bringup] stopped: zero output sent', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
