"""rm_robot executable: ``rm_robot --ros-args --params-file robot.yaml``."""

from __future__ import annotations

import sys

import rclpy
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.signals import SignalHandlerOptions

from rm_base.errors import ConfigError
from rm_base.host.node import NODE_NAME, ExecutorKind, RobotHost
from rm_base.ros_env import init_error_line, params_file_error, prepare_ros_process

# How long one spin_once may block [s]; bounds the reaction to SIGINT/SIGTERM.
_SPIN_TIMEOUT = 0.1


def make_executor(node: RobotHost) -> Executor:
    """Return the executor for node's ROS callbacks, as its ``executor`` parameter says.

    The executor only runs ROS callbacks (subscriptions, services, the state timer); the
    plugins tick in their own threads. EventsExecutor is the default: with
    /actuator_states at 1 kHz it used 14 % of a core against 38 % for the
    SingleThreadedExecutor (rm_robot with a 200 Hz plugin: 20-24 % against 56-73 %),
    measured here on rclpy 7.1.6. Its spin() ignores SIGINT, and spin() from a thread
    received nothing at all, so callers loop on spin_once(timeout_sec=...).
    """
    if node.executor_kind is ExecutorKind.EVENTS:
        return EventsExecutor(context=node.context)
    return SingleThreadedExecutor(context=node.context)


def main(args: list[str] | None = None) -> int:
    """Run rm_robot until SIGINT/SIGTERM; return the exit status (1 on a config error)."""
    prepare_ros_process()
    # rclpy's signal handlers would shut the context down before the plugins could
    # publish zero output; Python's KeyboardInterrupt leaves that to the finally below.
    bad_file = params_file_error(sys.argv if args is None else args)
    if bad_file is not None:
        print(f'[{NODE_NAME}] configuration error: {bad_file}', file=sys.stderr)
        return 1
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RuntimeError as err:  # rcl's RCLError, e.g. a params file that is not YAML
        print(f'[{NODE_NAME}] configuration error: {init_error_line(err)}', file=sys.stderr)
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
    try:
        while rclpy.ok(context=node.context):
            executor.spin_once(timeout_sec=_SPIN_TIMEOUT)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        # Every plugin off (zero output on /actuator_cmd) while the context still works.
        node.shutdown()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
