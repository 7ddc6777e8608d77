"""The rclpy side shared by the rmcli verbs: a private node, graph look-ups, stop signals."""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from rm_base.ros.env import prepare_ros_process

from .errors import CliError

if TYPE_CHECKING:
    from rclpy.node import Node

DISCOVERY_TIMEOUT_S = 5.0
"""Longest wait [s] for a topic to show up when its type is taken from the graph.

Discovery is often immediate, but a new process regularly needs one announcement period
of the others (measured here: ~2-2.5 s, Fast DDS, localhost only) and more under CPU
steal. The wait ends as soon as the topic is seen, so only a missing topic pays it all.
"""

_POLL_PERIOD_S = 0.05


@contextmanager
def cli_node(verb: str, *, name: str | None = None) -> Iterator[Node]:
    """Yield a hidden node in a private, initialised rclpy context; shut both down after.

    Discovery stays on localhost unless ROS_AUTOMATIC_DISCOVERY_RANGE is set (network
    rule), and SIGTERM ends the verb like SIGINT (rm_base.ros.env).

    Args:
        verb: short name for the node, e.g. ``'topic_pub'``.
        name: node name to use instead of the hidden ``_rmcli_<verb>_<pid>``.
    """
    from rclpy.exceptions import InvalidNodeNameException
    from rclpy.validate_node_name import validate_node_name

    node_name = name or f'_rmcli_{verb}_{os.getpid()}'
    try:
        validate_node_name(node_name)
    except InvalidNodeNameException as err:
        raise CliError(f"invalid node name '{name}': {' '.join(str(err).split())}") from None
    prepare_ros_process()
    import rclpy
    from rclpy.context import Context
    from rclpy.signals import SignalHandlerOptions

    context = Context()
    # rclpy's own SIGINT handler would shut the context down under our feet (see
    # rm_base.ros.env); Python's KeyboardInterrupt lets each verb finish cleanly instead.
    # args: not sys.argv, in which rcl would take `--remap /a:=/b` for its own (deprecated)
    # remap syntax and warn; rmcli has no ROS arguments of its own.
    rclpy.init(args=['rmcli'], context=context, signal_handler_options=SignalHandlerOptions.NO)
    try:
        # Hidden name (leading underscore), like ros2cli's '_ros2cli_<pid>' nodes.
        node = rclpy.create_node(node_name, context=context, start_parameter_services=False)
        try:
            yield node
        finally:
            node.destroy_node()
    finally:
        context.try_shutdown()


def expand_topic(node: Node, topic: str) -> str:
    """Return the fully qualified name of topic as seen from node (``chassis_cmd`` -> ``/...``).

    Raises:
        CliError: the name is not a valid topic name.
    """
    from rclpy.exceptions import InvalidTopicNameException
    from rclpy.expand_topic_name import expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name

    try:
        expanded = expand_topic_name(topic, node.get_name(), node.get_namespace())
        validate_full_topic_name(expanded)
    except (InvalidTopicNameException, ValueError) as err:
        raise CliError(f"invalid topic name '{topic}': {' '.join(str(err).split())}") from None
    return expanded


def wait_for_topic_types(node: Node, topic: str, timeout_s: float | None) -> list[str]:
    """Poll the graph until topic appears (or timeout_s passes); return its types.

    Args:
        node: node whose graph view is used.
        topic: fully qualified topic name.
        timeout_s: longest wait [s]; None waits until the topic appears.

    Returns:
        The topic's type names, empty if it did not appear in time.
    """
    deadline = None if timeout_s is None else time.monotonic() + timeout_s
    while True:
        for name, types in node.get_topic_names_and_types():
            if name == topic:
                return list(types)
        if deadline is not None and time.monotonic() >= deadline:
            return []
        time.sleep(_POLL_PERIOD_S)


def wait_until_heard(
    publishers: Iterable[Any], timeout_s: float, stop: Callable[[], bool] = lambda: False,
    sleep: Callable[[float], None] = time.sleep, clock: Callable[[], float] = time.monotonic,
) -> bool:
    """Wait until every publisher has a subscriber, at most timeout_s or until stop().

    Returns whether they all have one.
    """
    publishers = list(publishers)
    deadline = clock() + timeout_s
    while not all(p.get_subscription_count() > 0 for p in publishers):
        if stop() or clock() >= deadline:
            return False
        sleep(_POLL_PERIOD_S)
    return True


def resolve_topic_type(
    node: Node, topic: str, timeout_s: float | None = DISCOVERY_TIMEOUT_S
) -> str:
    """Return the one type of a topic from the live graph.

    Raises:
        CliError: the topic did not appear within timeout_s, or it has several types.
    """
    types = wait_for_topic_types(node, topic, timeout_s)
    if not types:
        raise CliError(
            f"topic '{topic}' is not on the ROS graph (waited {timeout_s:g} s for discovery, "
            f'ROS_DOMAIN_ID={os.environ.get("ROS_DOMAIN_ID", "0")}); '
            'give its type, e.g. rm_msgs/msg/ChassisCmd'
        )
    if len(types) > 1:
        raise CliError(
            f"topic '{topic}' has more than one type ({', '.join(types)}); give the type to use"
        )
    return types[0]


@contextmanager
def stop_on_signals() -> Iterator[threading.Event]:
    """Yield an Event that SIGINT/SIGTERM set, instead of raising KeyboardInterrupt.

    For loops that must not be interrupted half-way (a bag write): they poll the event and
    stop at a clean point. The previous handlers are restored on exit.
    """
    stop = threading.Event()
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}

    def handler(signum, frame):
        stop.set()

    for sig in previous:
        signal.signal(sig, handler)
    try:
        yield stop
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


def spin_reporting(node: Node, received: Callable[[], int], stats: Callable[[int], Any],
                   period_ns: int = 1_000_000_000) -> None:
    """Spin node until its context ends, printing ``stats(now_ns).format()`` once a period.

    Only while messages arrive (``received()`` grew since the last line), as ros2's topic hz
    and bw print; stats may return None (nothing to say yet).
    """
    from rclpy.executors import SingleThreadedExecutor

    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    printed_at, printed_count = time.monotonic_ns(), 0
    try:
        while node.context.ok():
            executor.spin_once(timeout_sec=0.1)
            now = time.monotonic_ns()
            if now - printed_at < period_ns or received() == printed_count:
                continue
            window = stats(now)
            if window is not None:
                print(window.format(), flush=True)
                printed_at, printed_count = now, received()
    finally:
        executor.shutdown()
