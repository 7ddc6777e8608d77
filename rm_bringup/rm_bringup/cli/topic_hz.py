"""``rmcli topic hz``: print the receive rate of a topic, like ``ros2 topic hz``.

Statistics over a window of the last N inter-arrival times, printed about once a second
while messages arrive: mean rate, min/max interval and its standard deviation. Arrival
times come from the monotonic clock (ros2 uses the ROS clock, i.e. wall time unless
use_sim_time). Not implemented: ``--filter``, ``--wall-time``, several topics at once.
"""

from __future__ import annotations

import argparse
import math
import time
from collections import deque
from dataclasses import dataclass

from .errors import CliError
from .interfaces import get_message_class
from .options import positive_int
from .ros_node import cli_node, expand_topic, spin_reporting, wait_for_topic_types

DEFAULT_WINDOW_SIZE = 10000


@dataclass(frozen=True)
class RateStats:
    """Statistics of the intervals between messages."""

    rate_hz: float  # 1 / mean interval
    min_s: float  # shortest interval [s]
    max_s: float  # longest interval [s]
    std_dev_s: float  # population standard deviation of the intervals [s]
    window: int  # number of intervals used

    def format(self) -> str:
        """The two lines ``ros2 topic hz`` prints."""
        return (
            f'average rate: {self.rate_hz:.3f}\n'
            f'\tmin: {self.min_s:.3f}s max: {self.max_s:.3f}s std dev: {self.std_dev_s:.5f}s '
            f'window: {self.window}'
        )


class RateWindow:
    """Keeps the last window_size intervals between arrival times [ns]."""

    def __init__(self, window_size: int = DEFAULT_WINDOW_SIZE) -> None:
        self._intervals_ns: deque[int] = deque(maxlen=window_size)
        self._last_ns: int | None = None
        self.received = 0

    def add(self, arrival_ns: int) -> None:
        """Record one arrival; a time going backwards restarts the statistics."""
        self.received += 1
        if self._last_ns is not None and arrival_ns >= self._last_ns:
            self._intervals_ns.append(arrival_ns - self._last_ns)
        elif self._last_ns is not None:
            self._intervals_ns.clear()
        self._last_ns = arrival_ns

    def stats(self) -> RateStats | None:
        """Statistics of the current window, or None before the second message."""
        n = len(self._intervals_ns)
        if n == 0:
            return None
        mean_ns = sum(self._intervals_ns) / n
        std_ns = math.sqrt(sum((x - mean_ns) ** 2 for x in self._intervals_ns) / n)
        return RateStats(
            rate_hz=1e9 / mean_ns if mean_ns > 0 else 0.0,
            min_s=min(self._intervals_ns) * 1e-9,
            max_s=max(self._intervals_ns) * 1e-9,
            std_dev_s=std_ns * 1e-9,
            window=n,
        )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``topic hz``."""
    parser.add_argument('topic_name', help="Name of the ROS topic to listen to (e.g. '/odom')")
    parser.add_argument(
        '--window',
        '-w',
        dest='window_size',
        type=positive_int,
        default=DEFAULT_WINDOW_SIZE,
        metavar='WINDOW',
        help='window size, in # of messages, for calculating rate '
        f'(default: {DEFAULT_WINDOW_SIZE})',
    )


def run(args: argparse.Namespace) -> int:
    """Print the rate about once a second until Ctrl-C."""
    from rclpy.qos import qos_profile_sensor_data

    from .qos import adapt_to_publishers

    window = RateWindow(args.window_size)
    with cli_node('topic_hz') as node:
        topic = expand_topic(node, args.topic_name)
        types = wait_for_topic_types(node, topic, timeout_s=None)  # like ros2: until it appears
        if len(types) > 1:
            raise CliError(f"topic '{topic}' has more than one type ({', '.join(types)})")
        msg_class = get_message_class(types[0])
        offered = [info.qos_profile for info in node.get_publishers_info_by_topic(topic)]
        qos, _ = adapt_to_publishers(qos_profile_sensor_data, offered)
        # raw=True: no deserialization, so high rates are measured, not the CPU's limit.
        node.create_subscription(
            msg_class, topic, lambda _raw: window.add(time.monotonic_ns()), qos, raw=True
        )
        spin_reporting(node, lambda: window.received, lambda now: window.stats())
    return 0
