"""rm_robot executable: ``rm_robot --ros-args --params-file robot.yaml``."""

from __future__ import annotations

import sys

from rclpy.executors import Executor, SingleThreadedExecutor
from rclpy.experimental import EventsExecutor

from rm_base.host.node import NODE_NAME, ExecutorKind, RobotHost
from rm_base.ros.node_main import run_node

USAGE = """usage: rm_robot --ros-args --params-file ROBOT.yaml
                [--params-file MORE.yaml] [-p NAME:=VALUE]

Runs the robot's plugins (the rm_robot section of the files: plugins, their parameters,
command sources) as the node rm_robot, fed by can_bridge's joint states over DDS. Every
parameter: docs/PARAMETERS.md."""


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
    return run_node(NODE_NAME, args, RobotHost, make_executor, usage=USAGE)


if __name__ == '__main__':
    sys.exit(main())
