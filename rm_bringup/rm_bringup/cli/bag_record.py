"""``rmcli bag record``: record topics to a rosbag2 bag (MCAP or sqlite3) through rosbags.

Like ``ros2 bag record``: topics are discovered while recording (every
``--polling-interval`` ms), a topic is subscribed once a publisher offers it, with QoS
adapted to all its publishers, and their offered QoS profiles go into metadata.yaml.
Messages are written as received (raw CDR, ``raw=True``), stamped with the receive time.
SIGINT/SIGTERM stop at a clean point and close the bag, so it is complete and readable.
Types come from rosbags' Jazzy store or the installed .msg files (bag_types).

Not implemented: services, compression, bag splitting, snapshot mode, QoS override files.
"""

from __future__ import annotations

import argparse
import datetime
import re
import sys
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from .bag_types import BagTypes
from .errors import BagError, CliError, MessageTypeError, UsageError
from .interfaces import get_message_class
from .options import positive_int

STORAGES = ('mcap', 'sqlite3')
_SPIN_PERIOD_S = 0.05
_DEFAULT_DEPTH = 10
_DRAIN_MAX_S = 0.5
_DRAIN_IDLE_SPINS = 3


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``bag record``."""
    parser.add_argument('topics_positional', nargs='*', metavar='topic', help='Topics to record')
    parser.add_argument(
        '--topics',
        nargs='+',
        default=[],
        metavar='Topic',
        help='Space-delimited list of topics to record.',
    )
    parser.add_argument(
        '-a', '--all', action='store_true', help='Record all topics (excluding hidden topics).'
    )
    parser.add_argument('--all-topics', action='store_true', help='Same as --all (no services).')
    parser.add_argument(
        '-e',
        '--regex',
        default='',
        help='Record only topics containing provided regular expression. '
        'Note: --all or --all-topics will override --regex.',
    )
    parser.add_argument(
        '--exclude-regex',
        default='',
        help='Exclude topics containing provided regular expression. '
        'Works on top of --all, --all-topics, or --regex.',
    )
    parser.add_argument(
        '--exclude-topics',
        nargs='+',
        default=[],
        metavar='Topic',
        help='Space-delimited list of topics not being recorded.',
    )
    parser.add_argument(
        '--include-hidden-topics',
        action='store_true',
        help='Discover and record hidden topics as well.',
    )
    parser.add_argument(
        '--no-discovery',
        action='store_true',
        help='Disables topic auto discovery during recording: only topics present at startup '
        'will be recorded.',
    )
    parser.add_argument(
        '-p',
        '--polling-interval',
        type=positive_int,
        default=100,
        metavar='MS',
        help='Time in ms to wait between querying available topics for recording (default: 100)',
    )
    parser.add_argument(
        '-o',
        '--output',
        help='Destination of the bag to create, defaults to a timestamped folder in the '
        'current directory.',
    )
    parser.add_argument(
        '-s',
        '--storage',
        choices=STORAGES,
        default='mcap',
        help="Storage identifier to be used, defaults to 'mcap'.",
    )


def _is_hidden(topic: str) -> bool:
    return any(part.startswith('_') for part in topic.split('/'))


@dataclass(frozen=True)
class TopicSelection:
    """Which topics to record, with rosbag2's rules (regex: search anywhere in the name)."""

    topics: frozenset[str] = frozenset()
    all_topics: bool = False
    regex: re.Pattern | None = None
    exclude_regex: re.Pattern | None = None
    exclude_topics: frozenset[str] = frozenset()
    include_hidden: bool = False

    def wants(self, topic: str) -> bool:
        """Whether to record a fully qualified topic name."""
        if topic in self.exclude_topics:
            return False
        if self.exclude_regex is not None and self.exclude_regex.search(topic):
            return False
        if topic in self.topics:
            return True
        if self.all_topics or (self.regex is not None and self.regex.search(topic)):
            return self.include_hidden or not _is_hidden(topic)
        return False


def selection_from_args(args: argparse.Namespace) -> TopicSelection:
    """Build and check the topic selection of the command line.

    Raises:
        UsageError: nothing to record, an exclusion without a pattern to apply to, or a
            bad regular expression.
    """
    topics = [*args.topics_positional, *args.topics]
    all_topics = args.all or args.all_topics
    if not (topics or all_topics or args.regex):
        raise UsageError('need to specify topics, --all, --all-topics or --regex')
    if (args.exclude_regex or args.exclude_topics) and not (all_topics or args.regex):
        raise UsageError('--exclude-regex and --exclude-topics need --all, --all-topics or --regex')

    def compile_pattern(pattern: str) -> re.Pattern | None:
        if not pattern:
            return None
        try:
            return re.compile(pattern)
        except re.error as err:
            raise UsageError(f"invalid regular expression '{pattern}': {err}") from None

    def absolute(topic: str) -> str:
        return topic if topic.startswith('/') else f'/{topic}'

    return TopicSelection(
        topics=frozenset(map(absolute, topics)),
        all_topics=all_topics,
        regex=compile_pattern(args.regex),
        exclude_regex=compile_pattern(args.exclude_regex),
        exclude_topics=frozenset(map(absolute, args.exclude_topics)),
        include_hidden=args.include_hidden_topics,
    )


class Recorder:
    """Subscribes to the selected topics as they appear and writes what arrives."""

    def __init__(self, node, writer, types: BagTypes, selection: TopicSelection) -> None:
        """Record into an open rosbags Writer through node."""
        self._node = node
        self._writer = writer
        self._types = types
        self._selection = selection
        self._clock = node.get_clock()
        self._handled: set[str] = set()  # subscribed or skipped for good
        self.subscribed: list[str] = []
        self.counts: dict[str, int] = {}

    def discover(self) -> None:
        """Subscribe to every selected topic that has a publisher now."""
        for topic, types in self._node.get_topic_names_and_types():
            if topic in self._handled or not self._selection.wants(topic):
                continue
            publishers = self._node.get_publishers_info_by_topic(topic)
            if not publishers:
                continue  # like rosbag2: wait for a publisher to know the QoS to ask for
            if len(types) != 1:
                self._skip(topic, f'it has more than one type ({", ".join(types)})')
                continue
            self._subscribe(topic, types[0], [info.qos_profile for info in publishers])
            self._check_hash(topic, types[0], publishers)

    def _skip(self, topic: str, reason: str) -> None:
        self._handled.add(topic)
        print(f'rmcli: warning: not recording {topic}: {reason}', file=sys.stderr, flush=True)

    def _subscribe(self, topic: str, msgtype: str, offered: list) -> None:
        from rclpy.qos import QoSProfile

        from .qos import adapt_to_publishers, to_bag_qos

        try:
            msg_class = get_message_class(msgtype)
            self._types.ensure(msgtype)
        except (MessageTypeError, BagError) as err:
            self._skip(topic, str(err))
            return
        connection = self._writer.add_connection(
            topic,
            msgtype,
            typestore=self._types.typestore,
            offered_qos_profiles=[to_bag_qos(profile) for profile in offered],
        )
        qos, warnings = adapt_to_publishers(QoSProfile(depth=_DEFAULT_DEPTH), offered)
        for warning in warnings:
            print(f'rmcli: warning: {topic}: {warning}', file=sys.stderr)
        self._node.create_subscription(
            msg_class, topic, partial(self._on_message, topic, connection), qos, raw=True
        )
        self._handled.add(topic)
        self.subscribed.append(topic)
        self.counts[topic] = 0
        print(f"Subscribed to topic '{topic}'", flush=True)

    def _check_hash(self, topic: str, msgtype: str, publishers: list) -> None:
        # The definition written comes from the installed .msg; a publisher built from
        # another version of it would make the bag lie about its data.
        if topic not in self.counts:
            return
        ours = self._types.typestore.hash_rihs01(msgtype)
        for info in publishers:
            theirs = str(info.topic_type_hash)
            if theirs.startswith('RIHS01_') and theirs != ours:
                print(
                    f'rmcli: warning: {topic}: publisher {info.node_name} uses another definition '
                    f'of {msgtype} ({theirs}) than the installed one ({ours})',
                    file=sys.stderr,
                )

    def _on_message(self, topic: str, connection, data: bytes) -> None:
        self._writer.write(connection, self._clock.now().nanoseconds, data)
        self.counts[topic] += 1


def record(executor, recorder: Recorder, stop, poll_period_s: float | None) -> None:
    """Spin the recorder until stop is set, then write what already arrived.

    Args:
        executor: executor of the recorder's node.
        recorder: subscribes and writes.
        stop: threading.Event set by SIGINT/SIGTERM.
        poll_period_s: period of topic discovery [s]; None discovers at the start only.
    """
    recorder.discover()
    next_poll = None if poll_period_s is None else time.monotonic() + poll_period_s
    while not stop.is_set():
        executor.spin_once(timeout_sec=_SPIN_PERIOD_S)
        if poll_period_s is not None and next_poll is not None and time.monotonic() >= next_poll:
            recorder.discover()
            next_poll = time.monotonic() + poll_period_s
    _drain(executor, recorder)


def _drain(executor, recorder: Recorder) -> None:
    """Write what arrived before the stop signal but has not been handled yet."""
    deadline = time.monotonic() + _DRAIN_MAX_S
    idle_spins = 0
    while idle_spins < _DRAIN_IDLE_SPINS and time.monotonic() < deadline:
        before = sum(recorder.counts.values())
        executor.spin_once(timeout_sec=_SPIN_PERIOD_S / 5)
        idle_spins = idle_spins + 1 if sum(recorder.counts.values()) == before else 0


def run(args: argparse.Namespace) -> int:
    """Record until SIGINT/SIGTERM, then close the bag."""
    from rclpy.executors import SingleThreadedExecutor
    from rosbags.rosbag2 import StoragePlugin, Writer, WriterError

    from .ros_node import cli_node, stop_on_signals

    selection = selection_from_args(args)
    output = Path(args.output or datetime.datetime.now().strftime('rosbag2_%Y_%m_%d-%H_%M_%S'))
    if output.exists():
        raise CliError(f"output folder '{output}' already exists")

    with cli_node('bag_record') as node, stop_on_signals() as stop:
        writer = Writer(output, version=9, storage_plugin=StoragePlugin[args.storage.upper()])
        try:
            writer.open()
        except (WriterError, OSError) as err:
            raise BagError(f"cannot create bag '{output}': {err}") from None
        recorder = Recorder(node, writer, BagTypes(), selection)
        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        print(f"Recording to '{output}' ({args.storage}); Ctrl-C to stop", flush=True)
        try:
            poll_period_s = None if args.no_discovery else args.polling_interval / 1000.0
            record(executor, recorder, stop, poll_period_s)
        finally:
            executor.shutdown()
            writer.close()  # also after an error: what was written stays readable
    total = sum(recorder.counts.values())
    print(f"Recording stopped: {total} messages on {len(recorder.subscribed)} topics in '{output}'")
    for topic in recorder.subscribed:
        print(f'  {topic}: {recorder.counts[topic]}')
    return 0
