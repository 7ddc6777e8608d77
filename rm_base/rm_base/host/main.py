"""rm_robot executable: ``rm_robot --ros-args --params-file robot.yaml``."""

from __future__ import annotations

import sys

import rclpy
from rclpy.executors import Executor, SingleThreadedExecutor
from rclpy.experimental import EventsExecutor

from rm_base.errors import ConfigError
from rm_base.host.node import NODE_NAME, ExecutorKind, RobotHost
from rm_base.node_main import init_ros, spin_until_shutdown
from rm_base.realtime import raise_edge_priority


def make_executor(node: RobotHost) -> Executor:
    """Return the executor for node's ROS callbacks, as its ``executor`` parameter says.

    The executor only runs the ROS edge (subscriptions, services, the state timer); the
    plugins run in the control loop's thread. EventsExecutor is the default: several
    times cheaper per callback than the SingleThreadedExecutor (docs/PERFORMANCE.md). Its
    spin() ignores SIGINT on rclpy 7.1.6, so callers loop on spin_once(timeout_sec=...).
    """
    if node.executor_kind is ExecutorKind.EVENTS:
        return EventsExecutor(context=node.context)
    return SingleThreadedExecutor(context=node.context)


def main(args: list[str] | None = None) -> int:
    """Run rm_robot until SIGINT/SIGTERM; return the exit status (1 on a config error)."""
    if not init_ros(NODE_NAME, args):
        return 1
    try:
        node = RobotHost()
    except ConfigError as err:
        # One line the operator can act on, not a traceback.
        print(f'[{NODE_NAME}] configuration error: {err}', file=sys.stderr)
        rclpy.try_shutdown()
        return 1
    except KeyboardInterrupt:
        rclpy.try_shutdown()
        return 0

    executor = make_executor(node)
    executor.add_node(node)
    raise_edge_priority(node.edge_priority)
    try:
        spin_until_shutdown(executor, node.context)
    finally:
        # Every plugin off (zero output on /actuator_cmd) while the context still works.
        node.shutdown()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
