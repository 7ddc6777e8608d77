"""rm_sim: the simulated motors, IMU and faults of a robot, in a process of their own.

    rm_sim --params-file standard.yaml --params-file standard_sim.yaml [--socket PATH]
    rm_sim --params-file robot_on_vcan.yaml --interface socketcan    # on vcan0, vcan1 ...

Reads the ``can_bridge`` section of the robot's parameter files (the same ``buses``,
``joints``, ``sim.*`` keys can_bridge reads), builds the simulated world and serves its
channels on an AF_UNIX socket (:mod:`rm_base.sim.server`), where can_bridge's buses with
``interface: rm_sim_socket`` connect as they would to socketcan; or, with ``--interface``,
on the python-can buses of that interface named as the channels (``socketcan``: the
kernel's vcan0 ..., where the robot's own socketcan buses are; :mod:`rm_base.sim.bus_peer`).
The world runs in real time on its own physics thread; the simulated Hi220 writes to its
pty as on a robot; a node ``rm_sim`` serves the fault services (``/rm_sim/<joint>/offline``,
``.../jam``, ``.../over_temperature``, ``.../garbage``, ``/rm_sim/<bus>/bus_off``;
:mod:`rm_base.bridge.sim_services`), takes the operator's remote on ``/rm_sim/remote``
(:mod:`rm_base.bridge.sim_remote`) and reports how its clock keeps up with the wall clock
on /diagnostics (``rm_sim: simulator``, at the bridge's ``diagnostics_rate``). Runs until
SIGINT/SIGTERM (or ``--duration``).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import can
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from rm_base.bridge.diagnostics import SimulatorReporter
from rm_base.bridge.params import settings_from_parameters
from rm_base.bridge.sim_config import world_config
from rm_base.bridge.sim_remote import SimRemoteInput
from rm_base.bridge.sim_services import SimFaultServices
from rm_base.config.param_files import load_parameters, parameters_for
from rm_base.errors import ConfigError
from rm_base.hardware.config import SAFETY_SCHEMA
from rm_base.ros.env import bounded_teardown, die_with_parent
from rm_base.ros.node_main import init_ros, spin_until_shutdown
from rm_base.sim import SimWorld
from rm_base.sim.bus_peer import BusPeer
from rm_base.sim.server import SimServer
from rm_base.sim.socket_bus import default_socket_path

NODE_NAME = 'rm_sim'
BRIDGE_SECTION = 'can_bridge'
#: The bridge's parameters that it declares itself (the rest are its config tree).
TYPED = frozenset({
    'publish_rate', 'diagnostics_rate', 'publish_frames', 'log_file', 'scheduler.rate_hz',
    'scheduler.receive_in_loop', 'scheduler.priority', 'scheduler.edge_priority',
    'scheduler.one_cpu', 'scheduler.cpu', 'scheduler.cpu_latency_us',
    'scheduler.collect_garbage',
    *(f'safety.{key}' for key in SAFETY_SCHEMA.names),
    'sim', 'sim.timing', 'sim.seed', 'sim.can', 'calibration.file', 'calibration.max_speed',
})


def bridge_parameters(files: Iterable[Path]) -> dict[str, Any]:
    """The can_bridge section's parameters of the files, later files overriding.

    Raises:
        ConfigError: a file is missing or not a ROS parameter file.
    """
    return parameters_for(load_parameters(files), BRIDGE_SECTION)


def build_world(params: Mapping[str, Any]) -> tuple[SimWorld, Any]:
    """The simulated world of a robot's bridge parameters, and the bridge's settings.

    Raises:
        ConfigError: the parameters are invalid (the message names the key).
    """
    typed = {k: v for k, v in params.items() if k in TYPED}
    typed['sim'] = True
    open_params = {k: v for k, v in params.items() if k not in TYPED}
    settings = settings_from_parameters(typed, open_params)
    if settings.sim is None:
        raise ConfigError('sim settings missing although sim is true')
    world = SimWorld.from_config(world_config(settings.hardware_config, settings.sim))
    return world, settings


def _report_clock(node: Node, world: SimWorld, rate_hz: float) -> None:
    """Publish ``rm_sim: simulator`` on /diagnostics at the bridge's diagnostics rate."""
    publisher = node.create_publisher(DiagnosticArray, '/diagnostics', 10)
    reporter = SimulatorReporter(NODE_NAME)

    def report() -> None:
        msg = DiagnosticArray(status=[reporter.status(SimulatorReporter.stats(world))])
        msg.header.stamp = node.get_clock().now().to_msg()
        publisher.publish(msg)

    node.create_timer(1.0 / rate_hz, report)


def _serve(world: SimWorld, interface: str | None, path: str) -> SimServer | BusPeer:
    """The socket server, or the world's channels on python-can buses of interface.

    Raises:
        can.CanError: a bus cannot be opened (no such channel: OSError 19 in socketcan).
    """
    if interface is None:
        return SimServer(world, path)
    return BusPeer.open(world, interface)


def parse_args(argv: list[str]) -> argparse.Namespace:
    """The command line (see the module docstring)."""
    parser = argparse.ArgumentParser(prog=NODE_NAME, description=__doc__.split('\n\n')[0])
    parser.add_argument('--params-file', action='append', required=True, type=Path,
                        help='robot parameter file (repeat: the sim overlay after the robot)')
    parser.add_argument(
        '--socket', default=None,
        help='socket path (default $RM_SIM_SOCKET, else /tmp/rm_sim_<domain>/can.sock)',
    )
    parser.add_argument(
        '--interface', default=None,
        help='serve each channel on the python-can bus of this interface named as it '
        '(e.g. socketcan: vcan0) instead of the socket',
    )
    parser.add_argument('--duration', type=float, default=None, help='stop after seconds [s]')
    parser.add_argument('--parent-pid', type=int, default=None,
                        help='stop when this process (the one that started rm_sim) dies')
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Run the simulator until SIGINT/SIGTERM; return the exit status (1 on a config error)."""
    args = parse_args(sys.argv[1:] if argv is None else argv)
    if args.parent_pid is not None:
        die_with_parent(args.parent_pid)
    try:
        world, settings = build_world(bridge_parameters(args.params_file))
    except ConfigError as err:
        print(f'[{NODE_NAME}] configuration error: {err}', file=sys.stderr)
        return 1
    path = args.socket or default_socket_path()
    try:
        server = _serve(world, args.interface, path)
    except can.CanError as err:
        world.close()
        print(f'[{NODE_NAME}] {err}', file=sys.stderr)
        return 1
    if not init_ros(NODE_NAME, [NODE_NAME]):
        server.stop()
        world.close()
        return 1
    node = Node(NODE_NAME)
    SimFaultServices(
        node, world, [j.name for j in settings.hardware_config.joints],
        {b.name: str(b.channel) for b in settings.hardware_config.buses}, prefix='~/',
    )
    if world.remote is not None:  # the node keeps its subscription and timer
        SimRemoteInput(node, world, prefix='~/')
    _report_clock(node, world, settings.diagnostics_rate_hz)
    # Only the fault services and the remote's input run on this executor; the physics and
    # the sockets have threads of their own.
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    deadline = None if args.duration is None else time.monotonic() + args.duration
    try:
        world.start()
        server.start()
        where = f'on {args.interface}' if args.interface else f'at {path}'
        print(f'[{NODE_NAME}] {", ".join(sorted(world.channels))} {where}', flush=True)
        spin_until_shutdown(
            executor, on_tick=lambda: deadline is None or time.monotonic() < deadline
        )
    finally:
        server.stop()
        world.close()
        with bounded_teardown():
            executor.shutdown()
            node.destroy_node()
            rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
