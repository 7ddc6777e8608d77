"""``rmcli topic list``: the topics on the graph, like ``ros2 topic list`` (no daemon).

Without ros2cli's daemon, which has watched the graph for long, a new node sees the others
only as discovery reaches it. So the list is taken once it has settled: at least
``--spin-time``, then until no topic was added for a second (five seconds at most), instead
of after a fixed half second that, on a busy machine, silently misses topics.
"""

from __future__ import annotations

import argparse
import time

from .options import nonnegative_float
from .ros_node import cli_node

DEFAULT_SPIN_TIME_S = 0.5  # ros2cli's DirectNode default: the shortest wait
QUIET_S = 1.0  # no topic added this long: discovery has settled [s]
LONGEST_S = 5.0  # the longest wait [s]
_POLL_S = 0.05


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
        help=f'Shortest wait for discovery in seconds (default: {DEFAULT_SPIN_TIME_S}); the '
        f'list is taken once no topic was added for {QUIET_S:g} s ({LONGEST_S:g} s at most)',
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


#: Topics every node has, this one too: a graph of only these has not been discovered yet.
OWN_TOPICS = frozenset({'/rosout', '/parameter_events'})


def settled(read, shortest_s: float, quiet_s: float = QUIET_S, longest_s: float = LONGEST_S):
    """read()'s topics once no new one came for quiet_s (after shortest_s, by longest_s).

    A graph with nothing but this node's own topics is not settled: on a loaded machine
    the first announcement of the others can take longer than quiet_s.
    """
    start = time.monotonic()
    seen, changed = read(), start
    while True:
        now = time.monotonic()
        if now - start >= longest_s:
            return seen
        others = {name for name, _ in seen} - OWN_TOPICS
        if others and now - start >= shortest_s and now - changed >= quiet_s:
            return seen
        time.sleep(_POLL_S)
        current = read()
        if {name for name, _ in current} - {name for name, _ in seen}:
            changed = time.monotonic()
        seen = current


def run(args: argparse.Namespace) -> int:
    """Wait --spin-time for discovery, then print the topics."""
    with cli_node('topic_list') as node:
        names = settled(node.get_topic_names_and_types, args.spin_time)
        lines = format_topics(
            names,
            show_types=args.show_types,
            count_only=args.count_topics,
            include_hidden=args.include_hidden_topics,
        )
    for line in lines:
        print(line)
    return 0
