"""Start-up, spin loop and inbox node shared by the executables (can_bridge, rm_robot, ...).

``run_node`` is a one-node executable's whole life (can_bridge, rm_robot)::

    def main(args=None):
        return run_node('rm_robot', args, RobotHost, make_executor)

``inbox_node`` makes the never-spun node a control loop takes subscriptions from.
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Callable, Sequence
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from rm_base.errors import ConfigError
from rm_base.ros.env import (
    bounded_teardown,
    init_error_line,
    params_file_error,
    prepare_ros_process,
)
from rm_base.runtime.realtime import prepare_loop_process


def inbox_node(owner: Node) -> Node:
    """A node beside owner (``<name>_inbox``, same namespace and context) for an Inbox.

    No executor may spin it: the control loop takes its subscriptions itself
    (:class:`rm_base.plugin.inbox.Inbox`). No parameter services: it has no parameters.
    """
    return Node(
        f'{owner.get_name()}_inbox',
        namespace=owner.get_namespace(),
        context=owner.context,
        start_parameter_services=False,
    )


# How long one spin_once may block [s]; bounds the reaction to SIGINT/SIGTERM.
SPIN_TIMEOUT = 0.1


def init_ros(name: str, args: Sequence[str] | None) -> bool:
    """Prepare the process and ``rclpy.init``; on a bad parameter file print one line.

    Args:
        name: executable name for the error line.
        args: command line for rclpy (None: ``sys.argv``).

    Returns:
        True if rclpy is initialised; False after printing the configuration error.
    """
    prepare_ros_process()
    bad_file = params_file_error(sys.argv if args is None else args)
    if bad_file is not None:
        print(f'[{name}] configuration error: {bad_file}', file=sys.stderr)
        return False
    try:
        # rclpy's signal handlers would shut the context down before the node could send
        # its zero output; Python's KeyboardInterrupt leaves the shutdown to the caller.
        rclpy.init(
            args=None if args is None else list(args),
            signal_handler_options=SignalHandlerOptions.NO,
        )
    except RuntimeError as err:  # rcl's RCLError, e.g. a params file rcl cannot parse
        print(f'[{name}] configuration error: {init_error_line(err)}', file=sys.stderr)
        return False
    return True


def spin_until_shutdown(
    executor: Executor,
    context: Context | None = None,
    *,
    on_tick: Callable[[], bool] | None = None,
    timeout_sec: float = SPIN_TIMEOUT,
) -> None:
    """Spin until Ctrl-C, SIGTERM or context shutdown (or on_tick returns False).

    EventsExecutor.spin() ignores SIGINT on rclpy 7.1.6 (docs/ROS_FROM_WHEELS.md), so this loops on
    spin_once with a short timeout instead. While it spins (in the main thread), SIGINT
    and SIGTERM only set a flag that the loop reads after each spin_once: a
    KeyboardInterrupt raised inside a callback the executor was calling from C++ comes
    out of spin_once as pybind11's "Unable to convert call argument" RuntimeError (seen in
    1 of 2 Ctrl-C of bringup), not as a clean stop. The previous handlers are back when it
    returns, so a second Ctrl-C during the shutdown interrupts as usual.

    Args:
        executor: the executor with the node(s) added.
        context: the context to watch (default: rclpy's global one).
        on_tick: called after every spin_once; returning False stops the loop.
        timeout_sec: longest block of one spin_once [s]; bounds the reaction to a signal.
    """
    stop = threading.Event()
    previous = {}
    if threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, signal.SIGTERM):
            previous[signum] = signal.signal(signum, lambda *_: stop.set())
    try:
        while not stop.is_set() and rclpy.ok(context=context):
            executor.spin_once(timeout_sec=timeout_sec)
            if on_tick is not None and on_tick() is False:
                break
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def run_node(
    name: str,
    args: Sequence[str] | None,
    make_node: Callable[[], Any],
    make_executor: Callable[[Any], Executor],
    *,
    config_errors: tuple[type[BaseException], ...] = (ConfigError,),
    usage: str = '',
) -> int:
    """Run one node until SIGINT/SIGTERM; return the exit status (1 on a config error).

    A configuration error is one line the operator can act on, not a traceback. The
    node's other threads go below its loop's priority (``node.edge_priority``), idle CPUs
    are asked to wake quickly (``node.cpu_latency_us``) and the threads go onto one CPU
    (``node.cpu_index``; docs/ARCHITECTURE.md "Real-time priority"). On
    the way out the node's ``shutdown()`` (zero output on the wire or on /actuator_cmd)
    runs while the context still works.

    Args:
        name: node name (for the error line).
        args: command-line arguments (``sys.argv`` if None).
        make_node: builds the node once rclpy is initialised.
        make_executor: the executor for the node's ROS callbacks.
        config_errors: exceptions of ``make_node`` that are configuration errors.
        usage: what ``-h``/``--help`` before ``--ros-args`` prints (then exit 0).
    """
    argv = list(sys.argv[1:] if args is None else args)
    own = argv[:argv.index('--ros-args')] if '--ros-args' in argv else argv
    if '-h' in own or '--help' in own:
        print(usage or f'usage: {name} --ros-args --params-file ROBOT.yaml [-p NAME:=VALUE]')
        return 0
    if not init_ros(name, args):
        return 1
    try:
        node = make_node()
    except config_errors as err:
        print(f'[{name}] configuration error: {" ".join(str(err).split())}', file=sys.stderr)
        rclpy.try_shutdown()
        return 1
    except KeyboardInterrupt:
        rclpy.try_shutdown()
        return 0
    executor: Executor | None = None
    try:
        executor = make_executor(node)
        executor.add_node(node)
        prepare_loop_process(node.edge_priority, node.cpu_index, node.cpu_latency_us)
        spin_until_shutdown(executor, node.context)
    except KeyboardInterrupt:
        # a SIGINT before the spin took the signals over (the loop already runs): the
        # same clean stop, zero output first
        pass
    finally:
        node.shutdown()  # zero output first, unbounded: it is quick and it matters
        with bounded_teardown():
            if executor is not None:
                executor.shutdown()
            node.destroy_node()
            rclpy.try_shutdown()
    return 0
