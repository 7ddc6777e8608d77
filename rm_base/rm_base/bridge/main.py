"""can_bridge executable: ``can_bridge --ros-args --params-file robot.yaml [-p sim:=true]``."""

from __future__ import annotations

import logging
import sys

import rclpy
from rclpy.experimental import EventsExecutor

from rm_base.bridge.node import NODE_NAME, CanBridgeNode
from rm_base.errors import ConfigError
from rm_base.hardware import BusError
from rm_base.node_main import init_ros, spin_until_shutdown
from rm_base.realtime import raise_edge_priority, shorten_gil_switch_interval
from rm_base.ros_logging import forward_package_logging


def _one_line(err: BaseException) -> str:
    return ' '.join(str(err).split())


def main(args: list[str] | None = None) -> int:
    """Run can_bridge until SIGINT/SIGTERM; return the exit status (1 on a config error)."""
    if not init_ros(NODE_NAME, args):
        return 1
    shorten_gil_switch_interval()
    handler = forward_package_logging(NODE_NAME)
    try:
        node = CanBridgeNode()
    except (ConfigError, BusError) as err:
        # One line the operator can act on, not a traceback.
        print(f'[{NODE_NAME}] configuration error: {_one_line(err)}', file=sys.stderr)
        rclpy.try_shutdown()
        return 1
    except KeyboardInterrupt:
        rclpy.try_shutdown()
        return 0

    # The executor runs only the ROS callbacks (/actuator_cmd, the sim services, parameter
    # services): the 1 kHz loop is CanHardware's own thread and the states go out from the
    # node's publisher thread. EventsExecutor costs about a quarter of the
    # SingleThreadedExecutor's CPU per message (docs/ROS_FROM_WHEELS.md: 12 % vs 46 % of a
    # core at 1000 msg/s); its spin() ignores SIGINT on rclpy 7.1.6, hence spin_once in a loop.
    executor = EventsExecutor(context=node.context)
    executor.add_node(node)
    raise_edge_priority(node.settings.edge_priority)
    try:
        spin_until_shutdown(executor, node.context)
    finally:
        # Zero output on the wire (DISABLE to MIT motors) before anything else goes.
        node.destroy_node()
        executor.shutdown()
        rclpy.try_shutdown()
        logging.getLogger('rm_base').removeHandler(handler)
    return 0


if __name__ == '__main__':
    sys.exit(main())
