"""``rmcli topic pub``: publish a message given as YAML, like ``ros2 topic pub``.

Differences from ros2cli: the type may be left out (it is then taken from the live graph),
integer fields accept the message's constant names (``mode: GYRO``), and after the last
message the publisher also waits (bounded) for reliable subscribers to acknowledge it.
"""

from __future__ import annotations

import argparse
import time

from .errors import CliError, UsageError
from .interfaces import get_message_class, looks_like_type_name, type_name_of
from .message_yaml import fill_message, parse_values
from .options import nonnegative_int, positive_float
from .qos import add_qos_arguments, profile_from_args
from .ros_node import (
    DISCOVERY_TIMEOUT_S,
    UnheardWarning,
    cli_node,
    expand_topic,
    resolve_topic_type,
)

_WAIT_LOG_PERIOD_S = 1.0
_WAIT_POLL_S = 0.1
_ACK_TIMEOUT_S = 2.0
#: After our side matched the subscribers, a wait for theirs [s]. Discovery is two-way,
#: and a busy robot matched our writer 0.33 s after we had matched its reader: the
#: message waited for that, arrived with a stale stamp and was refused as stale.
MATCH_SETTLE_S = 1.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``topic pub``."""
    parser.add_argument(
        'topic_name', help="Name of the ROS topic to publish to (e.g. '/chassis_cmd')"
    )
    parser.add_argument(
        'message_type',
        nargs='?',
        help="Type of the ROS message (e.g. 'rm_msgs/msg/ChassisCmd'); taken from the graph "
        'when left out',
    )
    parser.add_argument(
        'values',
        nargs='?',
        help="Values to fill the message with in YAML format (e.g. '{mode: GYRO}'), otherwise "
        'the message will be published with default values. Integer fields take the names of '
        "the message's constants. 'header: auto' and '<time field>: now' stamp each message "
        'with the current time.',
    )
    parser.add_argument(
        '-r',
        '--rate',
        metavar='N',
        type=positive_float,
        default=1.0,
        help='Publishing rate in Hz (default: 1)',
    )
    parser.add_argument(
        '-p',
        '--print',
        metavar='N',
        type=int,
        default=1,
        help='Only print every N-th published message (default: 1; 0: never)',
    )
    group = parser.add_mutually_exclusive_group()
    group.add_argument('-1', '--once', action='store_true', help='Publish one message and exit')
    group.add_argument(
        '-t',
        '--times',
        type=nonnegative_int,
        default=0,
        help='Publish this number of times and then exit',
    )
    parser.add_argument(
        '-w',
        '--wait-matching-subscriptions',
        type=nonnegative_int,
        default=None,
        help='Wait until finding the specified number of matching subscriptions. '
        'Defaults to 1 when using "-1"/"--once"/"--times", otherwise defaults to 0.',
    )
    parser.add_argument(
        '--max-wait-time-secs',
        type=positive_float,
        default=None,
        help='Longest wait for the matching subscriptions (default: wait endlessly)',
    )
    parser.add_argument(
        '--keep-alive',
        metavar='N',
        type=positive_float,
        default=0.1,
        help='Keep publishing node alive for N seconds after the last msg (default: 0.1)',
    )
    parser.add_argument('-n', '--node-name', help='Name of the created publishing node')
    parser.add_argument(
        '--discovery-timeout',
        metavar='SECONDS',
        type=positive_float,
        default=DISCOVERY_TIMEOUT_S,
        help='Longest wait for the topic to appear when the type is left out '
        f'(default: {DISCOVERY_TIMEOUT_S:g})',
    )
    add_qos_arguments(parser, 'publish', 'default')


def split_type_and_values(first: str | None, second: str | None) -> tuple[str | None, str]:
    """Return (type name or None, YAML text) from the positionals after the topic.

    A single positional is the type when it looks like ``pkg/msg/Name``, else the values.
    """
    if first is None:
        return None, '{}'
    if second is None:
        return (first, '{}') if looks_like_type_name(first) else (None, first)
    return first, second


def run(args: argparse.Namespace) -> int:
    """Publish until --times/--once is done, or until Ctrl-C."""
    times = 1 if args.once else args.times
    wait_subscriptions = (
        args.wait_matching_subscriptions
        if args.wait_matching_subscriptions is not None
        else int(times != 0)
    )
    if wait_subscriptions == 0 and args.max_wait_time_secs is not None:
        raise UsageError(
            '--max-wait-time-secs is only effective with --wait-matching-subscriptions, '
            '--once or --times'
        )
    type_name, text = split_type_and_values(args.message_type, args.values)
    values = parse_values(text)
    if type_name is not None:
        # Check the type and the values before touching ROS: fast, clear errors.
        msg_class = get_message_class(type_name)
        msg = msg_class()
        stamp_setters = fill_message(msg, values)

    with cli_node('topic_pub', name=args.node_name) as node:
        topic = expand_topic(node, args.topic_name)
        if type_name is None:
            type_name = resolve_topic_type(node, topic, args.discovery_timeout)
            msg_class = get_message_class(type_name)
            msg = msg_class()
            stamp_setters = fill_message(msg, values)
        publisher = node.create_publisher(msg_class, topic, profile_from_args(args))
        unheard = UnheardWarning(node, publisher, type_name_of(msg_class))
        _wait_for_subscriptions(publisher, wait_subscriptions, args.max_wait_time_secs, unheard)
        print('publisher: beginning loop', flush=True)
        count = 0
        period_s = 1.0 / args.rate
        next_due = time.monotonic()
        while times == 0 or count < times:
            if stamp_setters:
                stamp = node.get_clock().now().to_msg()
                for set_stamp in stamp_setters:
                    set_stamp(stamp)
            count += 1
            if args.print and count % args.print == 0:
                print(f'publishing #{count}: {msg!r}\n', flush=True)
            publisher.publish(msg)
            if times and count >= times:
                break
            unheard.poll()  # a subscriber of another type or QoS would get none of these
            # Absolute deadlines keep the rate; after a stall, restart instead of bursting.
            next_due = max(next_due + period_s, time.monotonic())
            time.sleep(max(0.0, next_due - time.monotonic()))
        _flush(publisher, args.keep_alive)
    return 0


def _wait_for_subscriptions(
    publisher, count: int, max_wait_s: float | None, unheard: UnheardWarning, sleep=time.sleep
) -> None:
    """Until count subscribers matched, then MATCH_SETTLE_S for them to match us."""
    if count == 0:
        return
    start = time.monotonic()
    last_log = None
    while publisher.get_subscription_count() < count:
        now = time.monotonic()
        if last_log is None or now - last_log >= _WAIT_LOG_PERIOD_S:
            print(f'Waiting for at least {count} matching subscription(s)...', flush=True)
            last_log = now
        unheard.poll()
        if max_wait_s is not None and now - start >= max_wait_s:
            raise CliError(
                f'timed out waiting for subscribers: expected {count} subscriber(s) but only got '
                f'{publisher.get_subscription_count()} in {max_wait_s:g} s'
            )
        sleep(_WAIT_POLL_S)
    sleep(MATCH_SETTLE_S)


def _flush(publisher, keep_alive_s: float) -> None:
    """Let the last messages reach the subscribers before the node goes away."""
    from rclpy.duration import Duration

    # Reliable subscribers acknowledge what they got; best-effort ones return at once.
    publisher.wait_for_all_acked(Duration(seconds=max(keep_alive_s, _ACK_TIMEOUT_S)))
    time.sleep(keep_alive_s)
