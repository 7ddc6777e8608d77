"""``rmcli bag play``: publish the messages of a bag with their original relative timing.

Each topic gets an rclpy publisher of its type (class found by name, rosidl's importlib
convention) with the QoS its publishers offered when recorded (rosbag2's rule), and the
recorded CDR bytes are published as they are. Message i goes out
``(t_i - t_start) / rate`` after playback starts, on absolute deadlines, so delays do not
accumulate. Before starting, playback waits (``--wait-for-subscribers``, default 5 s) until
every publisher has matched a subscriber, so the first messages are not lost to discovery:
a new participant can need up to one announcement period of the others (~3 s with Fast
DDS on localhost) to see them.

``--remap FROM:=TO`` publishes a recorded topic under another name (a teleop bag recorded on
/cmd_vel replayed as /vel_cmd), as ros2 bag play's --remap does for topic names.

A topic recorded with an older definition of its type (a field added since) is decoded with
the recorded definition and rebuilt in the installed one, new fields at their defaults
(:mod:`.bag_convert`); playback says so per topic, and refuses a topic whose field changed
its kind.

``--clock [HZ]`` also publishes the bag's time on /clock (rosgraph_msgs/Clock, 40 Hz by
default, as ros2 bag play), advancing at ``--rate``, so nodes run with ``use_sim_time``
see the time the messages were recorded at: a stamped command replayed stays fresh. The
wait for subscribers then includes /clock's, so such a node has the bag's time from the
first message on.

``--restamp`` sets the ``header.stamp`` of every message that has one to the time it is
replayed at (this node's clock), so a robot that refuses commands older than their timeout
takes a recorded command stream as if it were sent now: the way to drive a live robot
from a bag. ``--clock`` is the other way, for nodes that run on the bag's time.

Without ``--topics``, a topic some other node publishes now (a live robot's states) is not
played, and that is said: replaying a recorded /chassis_state next to the live one would
mix the two. Name it in ``--topics`` to play it anyway.

Not implemented from ros2 bag play: keyboard controls, node-name remapping, services, QoS
override files, --playback-duration/until.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .bag_convert import Conversion, conversions
from .bag_io import open_bag, read_messages
from .bag_topics import by_topic, check_remaps, not_live, parse_remaps, select
from .errors import CliError, MessageTypeError
from .interfaces import get_message_class
from .options import nonnegative_float, positive_float

DEFAULT_WAIT_FOR_SUBSCRIBERS_S = 5.0
DEFAULT_CLOCK_HZ = 40.0
CLOCK_TOPIC = '/clock'
_ACK_TIMEOUT_S = 2.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``bag play``."""
    parser.add_argument('bag_path', help='Bag to open (folder, .mcap or .db3)')
    parser.add_argument(
        '-r',
        '--rate',
        type=positive_float,
        default=1.0,
        help='rate at which to play back messages. Valid range > 0.0.',
    )
    parser.add_argument(
        '-l',
        '--loop',
        action='store_true',
        help='enables loop playback when playing a bagfile: it starts back at the beginning '
        'on reaching the end and plays indefinitely.',
    )
    parser.add_argument(
        '--topics',
        type=str,
        default=[],
        nargs='+',
        help='topics to replay, separated by space. If none specified, all topics will be '
        'replayed.',
    )
    parser.add_argument(
        '--start-offset',
        type=nonnegative_float,
        default=0.0,
        metavar='SECONDS',
        help='Start the playback player this many seconds into the bag file.',
    )
    parser.add_argument(
        '-d',
        '--delay',
        type=nonnegative_float,
        default=0.0,
        metavar='SECONDS',
        help='Sleep duration before play (each loop), in seconds.',
    )
    parser.add_argument(
        '-m',
        '--remap',
        type=str,
        default=[],
        nargs='+',
        metavar='FROM:=TO',
        help='publish a recorded topic under another name, e.g. /cmd_vel:=/vel_cmd',
    )
    parser.add_argument(
        '--clock',
        type=positive_float,
        nargs='?',
        const=DEFAULT_CLOCK_HZ,
        default=None,
        metavar='HZ',
        help=f'publish the bag time on {CLOCK_TOPIC} at HZ (default {DEFAULT_CLOCK_HZ:g}) '
        'for nodes with use_sim_time',
    )
    parser.add_argument(
        '--restamp',
        action='store_true',
        help='stamp each message that has a header with the time it is replayed at (drive a '
        'live robot, whose commands time out, from a recorded command stream)',
    )
    parser.add_argument(
        '--wait-for-subscribers',
        type=nonnegative_float,
        metavar='SECONDS',
        default=DEFAULT_WAIT_FOR_SUBSCRIBERS_S,
        help='Longest wait for every topic to have a subscriber before starting '
        f'(default: {DEFAULT_WAIT_FOR_SUBSCRIBERS_S:g}; 0: start at once)',
    )


def run(args: argparse.Namespace) -> int:
    """Play the bag (again and again with --loop) until done or SIGINT/SIGTERM."""
    from .qos import offer_for_recorded
    from .ros_node import cli_node, stop_on_signals, wait_until_heard, why_unheard

    path = Path(args.bag_path)
    remaps = parse_remaps(args.remap)
    with open_bag(path) as reader:
        connections = select(reader.connections, args.topics, path)
        check_remaps(remaps, by_topic(connections))
        with cli_node('bag_play') as node, stop_on_signals() as stop:
            if not args.topics:  # named topics play whoever else publishes them
                connections = not_live(node, connections, remaps, path)
            publishers = {}
            for topic, conns in by_topic(connections).items():
                try:
                    msg_class = get_message_class(conns[0].msgtype)
                except MessageTypeError as err:
                    print(f'rmcli: warning: not playing {topic}: {err}', file=sys.stderr)
                    continue
                offered = [q for c in conns for q in c.ext.offered_qos_profiles]
                publishers[topic] = node.create_publisher(
                    msg_class, remaps.get(topic, topic), offer_for_recorded(offered)
                )
            if not publishers:
                raise CliError(f'nothing to play in {path}: no topic has a known message type')
            playable = [c for c in connections if c.topic in publishers]
            converted = conversions(playable)
            converted_by_topic = {c.topic: converted[c.id] for c in playable if c.id in converted}
            for topic, conversion in converted_by_topic.items():
                print(f'rmcli: {conversion.describe(topic)}', file=sys.stderr)
            restamp = None
            if args.restamp:
                restamp = {c.topic: Restamper(get_message_class(c.msgtype), node.get_clock())
                           for c in playable if has_header(get_message_class(c.msgtype))}
            clock = None
            if args.clock is not None:
                clock = ClockPublisher(node, args.clock)
            # /clock too: a sim-time subscriber that matched late would miss the first ticks
            waited = [*publishers.values(), *([clock.publisher] if clock is not None else [])]
            if not wait_until_heard(waited, args.wait_for_subscribers, stop.is_set):
                recorded = by_topic(playable)
                for topic, publisher in publishers.items():
                    if publisher.get_subscription_count() > 0:
                        continue
                    # a subscriber of another type (or QoS) would get none of them, silently
                    reason = why_unheard(node, publisher, recorded[topic][0].msgtype)
                    if reason is not None:
                        print(f'rmcli: warning: {reason}', file=sys.stderr)
            options = PlayOptions(args.rate, args.loop, args.start_offset, args.delay)
            played = play(
                reader, path, playable, publishers, options=options, stop=stop, clock=clock,
                converted=converted, restamp=restamp,
            )
            for publisher in publishers.values():
                _flush(publisher)
    print(f'Played {played} messages on {len(publishers)} topics')
    return 0


class ClockPublisher:
    """Publishes a time on /clock (rosgraph_msgs/Clock) every ``period_ns`` of wall time."""

    def __init__(self, node, rate_hz: float) -> None:
        from rclpy.qos import QoSProfile
        from rosgraph_msgs.msg import Clock

        self._msg_type = Clock
        # reliable, depth 1: matches rclpy's best-effort /clock subscription and a reliable one
        self.publisher = node.create_publisher(Clock, CLOCK_TOPIC, QoSProfile(depth=1))
        self.period_ns = round(1e9 / rate_hz)

    def publish(self, bag_ns: int) -> None:
        """Say that it is bag_ns [ns since the epoch]."""
        msg = self._msg_type()
        msg.clock.sec, msg.clock.nanosec = divmod(int(bag_ns), 1_000_000_000)
        self.publisher.publish(msg)


@dataclass(frozen=True)
class PlayOptions:
    """How to play: speed, repetition and where to start."""

    rate: float = 1.0  # playback speed factor (2: twice as fast)
    loop: bool = False  # start over at the end until stopped
    start_offset_s: float = 0.0  # skip this much of the bag's beginning [s]
    delay_s: float = 0.0  # wait before each pass [s]


def has_header(msg_class: Any) -> bool:
    """Whether a message class has a std_msgs/Header named header."""
    return msg_class.get_fields_and_field_types().get('header') == 'std_msgs/Header'


class Restamper:
    """Serialised message -> the same message stamped with clock's time now."""

    def __init__(self, msg_class: type, clock) -> None:
        from rclpy.serialization import deserialize_message, serialize_message

        self._class, self._clock = msg_class, clock
        self._deserialize, self._serialize = deserialize_message, serialize_message

    def __call__(self, raw: bytes) -> bytes:
        """raw, its header stamped now."""
        msg = self._deserialize(raw, self._class)
        msg.header.stamp = self._clock.now().to_msg()
        return self._serialize(msg)


def play(
    reader, path: Path, connections, publishers, *, options: PlayOptions, stop, clock=None,
    converted: dict[int, Conversion] | None = None, restamp: dict | None = None,
) -> int:
    """Publish the bag's messages with their relative timing; return how many were sent.

    Args:
        reader: an open rosbags Reader.
        path: the bag, for error messages.
        connections: the connections to play.
        publishers: topic -> object with ``publish(bytes)`` (an rclpy publisher).
        options: rate, loop, start offset and delay.
        stop: threading.Event that ends playback at once when set.
        clock: a ClockPublisher to give the bag time to (``--clock``), or None.
        converted: by connection id, how to rebuild its messages in the installed type.
        restamp: by topic, what stamps its messages with the replay time (``--restamp``).

    Raises:
        BagError: the bag is damaged part-way.
    """
    start_ns = reader.start_time + round(options.start_offset_s * 1e9)
    played = 0
    while not stop.is_set():
        if options.delay_s and stop.wait(options.delay_s):
            break
        played += _play_once(
            reader,
            path,
            connections,
            publishers=publishers,
            start_ns=start_ns,
            rate=options.rate,
            stop=stop,
            clock=clock,
            converted=converted or {},
            restamp=restamp or {},
        )
        if not options.loop:
            break
    return played


def _play_once(
    reader, path, connections, *, publishers, start_ns: int, rate: float, stop, clock=None,
    converted: dict[int, Conversion], restamp: dict,
) -> int:
    """Publish every message from start_ns on at its relative time; return how many.

    With a clock, the bag time (start_ns plus the time played, times rate) also goes out
    every clock period, between messages too.
    """
    count = 0
    t0 = time.monotonic_ns()
    next_tick = t0

    def tick(now: int, force: bool = False) -> int:
        """Publish the clock if due (or forced); return when it is next due."""
        nonlocal next_tick
        if force or now >= next_tick:
            clock.publish(start_ns + round((now - t0) * rate))
            next_tick = max(next_tick + clock.period_ns, now)
        return next_tick

    for connection, stamp_ns, raw in read_messages(reader, path, connections, start=start_ns):
        due_ns = t0 + (stamp_ns - start_ns) / rate
        while True:
            now = time.monotonic_ns()
            wake = due_ns if clock is None else min(due_ns, tick(now))
            remaining_s = (wake - now) * 1e-9
            if remaining_s > 0 and stop.wait(remaining_s):
                return count
            if stop.is_set():
                return count
            if time.monotonic_ns() >= due_ns:
                break
        if clock is not None:  # the clock reaches a message's time before it goes out
            tick(time.monotonic_ns(), force=True)
        conversion = converted.get(connection.id)
        data = bytes(raw) if conversion is None else conversion(raw)
        stamp = restamp.get(connection.topic)
        publishers[connection.topic].publish(data if stamp is None else stamp(data))
        count += 1
    return count


def _flush(publisher) -> None:
    from rclpy.duration import Duration

    publisher.wait_for_all_acked(Duration(seconds=_ACK_TIMEOUT_S))
