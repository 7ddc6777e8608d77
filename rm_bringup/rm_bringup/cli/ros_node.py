"""The rclpy side shared by the rmcli verbs: a private node, graph look-ups, stop signals."""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from rm_base.ros.env import bounded_teardown, prepare_ros_process

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
            with bounded_teardown():
                node.destroy_node()
    finally:
        with bounded_teardown():
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


def why_unheard(node: Node, publisher: Any, type_name: str) -> str | None:
    """Why the subscribers the graph shows on a publisher's topic do not match it, if so.

    DDS matches a publisher only with subscriptions of its type and of compatible QoS, and
    says nothing about the others: a message of the wrong type goes nowhere, silently.

    Args:
        node: the node the publisher belongs to.
        publisher: the rclpy publisher.
        type_name: its message type, ``pkg/msg/Name``.

    Returns:
        The subscribers' other types or the QoS conflict, naming their nodes; None when
        no subscriber is seen, or every one it sees could match.
    """
    from rclpy.qos import QoSCompatibility, qos_check_compatible

    topic = publisher.topic_name
    mine = node.get_fully_qualified_name()
    # the graph's view of our own QoS: a local profile leaves deadline and lease unset
    # where the graph gives them as infinite, and the check would take that for a conflict
    offered = [
        info.qos_profile for info in node.get_publishers_info_by_topic(topic)
        if f'{info.node_namespace.rstrip("/")}/{info.node_name}' == mine
    ]
    others: list[str] = []
    conflicts: list[str] = []
    for info in node.get_subscriptions_info_by_topic(topic):
        who = f'{info.node_namespace.rstrip("/")}/{info.node_name}'
        if who == mine:
            continue
        if info.topic_type != type_name:
            others.append(f'{info.topic_type} ({who})')
            continue
        if not offered:
            continue
        compatible, reason = qos_check_compatible(offered[0], info.qos_profile)
        if compatible == QoSCompatibility.ERROR:
            conflicts.append(f'{who}: {reason.replace("ERROR: ", "").strip().rstrip(";")}')
    if others:
        return (f'{topic} is subscribed as {", ".join(sorted(set(others)))}, not as '
                f'{type_name}: those subscribers never get these messages')
    if conflicts:
        return (f'{topic}: QoS that no subscriber accepts ({"; ".join(sorted(set(conflicts)))})'
                ': they never get these messages')
    return None


class UnheardWarning:
    """Says once, on stderr, when a publisher's subscribers cannot match it (why_unheard).

    Polled from a verb's loop while nothing has matched: discovery brings the others'
    subscriptions within a few announcement periods, so the first look may see none.
    """

    def __init__(self, node: Node, publisher: Any, type_name: str, period_s: float = 1.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self._node, self._publisher, self._type_name = node, publisher, type_name
        self._period_s, self._clock = period_s, clock
        self._next = clock()
        self.said: str | None = None

    def poll(self) -> None:
        """Look at the graph at most once a period while no subscription matched."""
        now = self._clock()
        if self.said is not None or now < self._next:
            return
        self._next = now + self._period_s
        if self._publisher.get_subscription_count() > 0:
            return
        reason = why_unheard(self._node, self._publisher, self._type_name)
        if reason is not None:
            self.said = reason
            print(f'rmcli: warning: {reason}', file=sys.stderr, flush=True)


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
