"""``rmcli topic list``: the topics on the graph, like ``ros2 topic list`` (no daemon)."""

from __future__ import annotations

import argparse
import time

from .options import nonnegative_float
from .ros_node import cli_node

DEFAULT_SPIN_TIME_S = 0.5  # ros2cli's DirectNode default


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``topic list``."""
    parser.add_argument(
        '-t', '--show-types', action='store_true', help='Additionally show the topic type'
    )
    parser.add_argument(
        '-c', '--count-topics', action='store_true', help='Only display the number of topics'
    )
    parser.add_argument(
        '--include-hidden-topics', action='store_true', help='Consider hidden topics as well'
    )
    parser.add_argument(
        '--spin-time',
        type=nonnegative_float,
        default=DEFAULT_SPIN_TIME_S,
        help=f'Spin time in seconds to wait for discovery (default: {DEFAULT_SPIN_TIME_S})',
    )


def format_topics(
    names_and_types: list[tuple[str, list[str]]],
    *,
    show_types: bool,
    count_only: bool,
    include_hidden: bool,
) -> list[str]:
    """Return the output lines for the graph's topic names and types."""
    from rclpy.topic_or_service_is_hidden import topic_or_service_is_hidden

    topics = sorted(
        (name, types)
        for name, types in names_and_types
        if include_hidden or not topic_or_service_is_hidden(name)
    )
    if count_only:
        return [str(len(topics))]
    if show_types:
        return [f'{name} [{", ".join(types)}]' for name, types in topics]
    return [name for name, _ in topics]


def run(args: argparse.Namespace) -> int:
    """Wait --spin-time for discovery, then print the topics."""
    with cli_node('topic_list') as node:
        time.sleep(args.spin_time)
        lines = format_topics(
            node.get_topic_names_and_types(),
            show_types=args.show_types,
            count_only=args.count_topics,
            include_hidden=args.include_hidden_topics,
        )
    for line in lines:
        print(line)
    return 0
