"""can_bridge executable: ``can_bridge --ros-args --params-file robot.yaml [-p sim:=true]``."""

from __future__ import annotations

import logging
import sys

from rclpy.executors import Executor
from rclpy.experimental import EventsExecutor

from rm_base.bridge.node import NODE_NAME, CanBridgeNode
from rm_base.errors import ConfigError
from rm_base.hardware import BusError
from rm_base.ros.log import forward_package_logging
from rm_base.ros.node_main import run_node

USAGE = """usage: can_bridge --ros-args --params-file ROBOT.yaml
                  [--params-file MORE.yaml] [-p NAME:=VALUE]

Runs the CAN hardware of the can_bridge section of the files (buses, joints, the 1 kHz
loop, safety) as the node can_bridge; -p sim:=true runs every bus on the simulator. Every
parameter: docs/PARAMETERS.md."""


def _executor(node: CanBridgeNode) -> Executor:
    # Only the ROS callbacks (/actuator_cmd, the sim services, parameter services): the
    # 1 kHz loop is CanHardware's own thread, the states go out from the node's publisher
    # thread. EventsExecutor: about a quarter of the SingleThreadedExecutor's CPU per
    # message (docs/ROS_FROM_WHEELS.md).
    return EventsExecutor(context=node.context)


def main(args: list[str] | None = None) -> int:
    """Run can_bridge until SIGINT/SIGTERM; return the exit status (1 on a config error)."""
    handler = forward_package_logging(NODE_NAME)
    try:
        return run_node(
            NODE_NAME, args, CanBridgeNode, _executor, config_errors=(ConfigError, BusError),
            usage=USAGE,
        )
    finally:
        logging.getLogger('rm_base').removeHandler(handler)


if __name__ == '__main__':
    sys.exit(main())
