"""``rmcli topic bw``: print the bandwidth a topic uses, like ``ros2 topic bw``.

Over a window of the last N messages (their serialised sizes and arrival times): the rate
in B/s, KB/s or MB/s and the mean, min and max message size, printed about once a second
while messages arrive.
"""

from __future__ import annotations

import argparse
import time
from collections import deque
from dataclasses import dataclass

from .errors import CliError
from .interfaces import get_message_class
from .options import positive_int
from .ros_node import cli_node, expand_topic, spin_reporting, wait_for_topic_types

DEFAULT_WINDOW_SIZE = 100  # ros2 topic bw's default


def _size(n: float) -> str:
    """``512 B``, ``1.50 KB``, ``2.00 MB`` (ros2's units: 1000, not 1024)."""
    if n < 1000:
        return f'{n:.0f} B'
    if n < 1_000_000:
        return f'{n / 1000:.2f} KB'
    return f'{n / 1_000_000:.2f} MB'


@dataclass(frozen=True)
class Bandwidth:
    """What the window holds: bytes per second and the message sizes."""

    bytes_per_s: float
    mean: float
    smallest: int
    largest: int
    window: int

    def format(self) -> str:
        """The two lines ``ros2 topic bw`` prints."""
        return (
            f'{_size(self.bytes_per_s)}/s from {self.window} messages\n'
            f'\tMessage size mean: {_size(self.mean)} min: {_size(self.smallest)} '
            f'max: {_size(self.largest)}'
        )


class BandwidthWindow:
    """The last window_size (arrival [ns], size [B]) pairs."""

    def __init__(self, window_size: int = DEFAULT_WINDOW_SIZE) -> None:
        self._samples: deque[tuple[int, int]] = deque(maxlen=window_size)
        self.received = 0

    def add(self, arrival_ns: int, size: int) -> None:
        """Record one message."""
        self.received += 1
        self._samples.append((arrival_ns, size))

    def stats(self, now_ns: int) -> Bandwidth | None:
        """The window's bandwidth up to now_ns, or None before a message."""
        if not self._samples:
            return None
        sizes = [size for _, size in self._samples]
        span_ns = now_ns - self._samples[0][0]
        return Bandwidth(
            bytes_per_s=sum(sizes) * 1e9 / span_ns if span_ns > 0 else 0.0,
            mean=sum(sizes) / len(sizes), smallest=min(sizes), largest=max(sizes),
            window=len(sizes),
        )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``topic bw``."""
    parser.add_argument('topic_name', help="Name of the ROS topic to listen to (e.g. '/odom')")
    parser.add_argument(
        '--window', '-w', dest='window_size', type=positive_int, default=DEFAULT_WINDOW_SIZE,
        metavar='WINDOW', help=f'window size, in # of messages (default: {DEFAULT_WINDOW_SIZE})',
    )


def run(args: argparse.Namespace) -> int:
    """Print the bandwidth about once a second until Ctrl-C."""
    from rclpy.qos import qos_profile_sensor_data

    from .qos import adapt_to_publishers

    window = BandwidthWindow(args.window_size)
    with cli_node('topic_bw') as node:
        topic = expand_topic(node, args.topic_name)
        types = wait_for_topic_types(node, topic, timeout_s=None)  # like ros2: until it appears
        if len(types) > 1:
            raise CliError(f"topic '{topic}' has more than one type ({', '.join(types)})")
        offered = [info.qos_profile for info in node.get_publishers_info_by_topic(topic)]
        qos, _ = adapt_to_publishers(qos_profile_sensor_data, offered)
        node.create_subscription(
            get_message_class(types[0]), topic,
            lambda raw: window.add(time.monotonic_ns(), len(raw)),  # type: ignore[arg-type]
            qos, raw=True,
        )
        print(f'Subscribed to [{topic}]', flush=True)
        spin_reporting(node, lambda: window.received, window.stats)
    return 0
