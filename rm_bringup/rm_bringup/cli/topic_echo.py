"""``rmcli topic echo``: print the messages of a topic as YAML (or CSV), like ros2's echo.

Differences from ros2cli: ``--field`` is checked against the type before subscribing, a
non-message field that is an array prints as a list, and ``--once`` with ``--timeout``
exits with an error when nothing arrived. Not implemented: ``--filter``, ``--raw``,
``--include-message-info``, ``--no-lost-messages``.
"""

from __future__ import annotations

import argparse
import sys
import time

from .errors import CliError
from .interfaces import get_message_class
from .message_yaml import check_field_path, get_field, message_to_csv, message_to_yaml
from .options import nonnegative_int, positive_float
from .qos import adapt_to_publishers, add_qos_arguments, profile_from_args, qos_overridden
from .ros_node import DISCOVERY_TIMEOUT_S, cli_node, expand_topic, resolve_topic_type

DEFAULT_TRUNCATE_LENGTH = 128
_SPIN_PERIOD_S = 0.1


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``topic echo``."""
    parser.add_argument(
        'topic_name', help="Name of the ROS topic to listen to (e.g. '/chassis_cmd')"
    )
    parser.add_argument(
        'message_type',
        nargs='?',
        help="Type of the ROS message (e.g. 'rm_msgs/msg/ChassisCmd'); taken from the graph "
        'when left out',
    )
    add_qos_arguments(parser, 'subscribe', 'sensor_data')
    parser.add_argument(
        '--csv',
        action='store_true',
        help='Output all recursive fields separated by commas (e.g. for plotting)',
    )
    parser.add_argument(
        '--field',
        type=str,
        default=None,
        help="Echo a selected field of a message. Use '.' to select sub-fields "
        "(e.g. 'accel.linear')",
    )
    parser.add_argument(
        '--full-length',
        '-f',
        action='store_true',
        help='Output all elements for arrays, bytes, and string with a length > '
        "'--truncate-length'",
    )
    parser.add_argument(
        '--truncate-length',
        '-l',
        type=nonnegative_int,
        default=DEFAULT_TRUNCATE_LENGTH,
        help=f'The length to truncate arrays, bytes, and string to '
        f'(default: {DEFAULT_TRUNCATE_LENGTH})',
    )
    parser.add_argument(
        '--no-arr', action='store_true', help="Don't print array fields of messages"
    )
    parser.add_argument(
        '--no-str', action='store_true', help="Don't print string fields of messages"
    )
    parser.add_argument(
        '--flow-style',
        action='store_true',
        help='Print collections in the flow style (not available with csv format)',
    )
    parser.add_argument(
        '--once', action='store_true', help='Print the first message received and then exit.'
    )
    parser.add_argument(
        '--timeout',
        metavar='N',
        type=positive_float,
        default=None,
        help='Stop after N seconds (with --once: fail if nothing arrived)',
    )
    parser.add_argument(
        '--discovery-timeout',
        metavar='SECONDS',
        type=positive_float,
        default=DISCOVERY_TIMEOUT_S,
        help='Longest wait for the topic to appear when the type is left out '
        f'(default: {DISCOVERY_TIMEOUT_S:g})',
    )


class Printer:
    """Formats each received message as the options ask and writes it to a stream."""

    def __init__(self, args: argparse.Namespace, stream=None) -> None:
        self._args = args
        self._field = _field_path(args.field)
        self._truncate = None if args.full_length else args.truncate_length
        self._stream = stream if stream is not None else sys.stdout
        self.count = 0

    @property
    def field(self) -> list[str] | None:
        """The selected field path, or None for whole messages."""
        return self._field

    def __call__(self, msg) -> None:
        """Print one message (or its selected field)."""
        value = get_field(msg, self._field) if self._field else msg
        self.count += 1
        if not hasattr(value, 'get_fields_and_field_types'):
            if isinstance(value, bytes | str | int | float | bool):
                text = str(value)
            else:
                text = str(list(value.tolist() if hasattr(value, 'tolist') else value))
            self._stream.write(f'{text}\n---\n')
        elif self._args.csv:
            self._stream.write(
                message_to_csv(
                    value,
                    truncate_length=self._truncate,
                    no_arr=self._args.no_arr,
                    no_str=self._args.no_str,
                )
                + '\n'
            )
        else:
            self._stream.write(
                message_to_yaml(
                    value,
                    truncate_length=self._truncate,
                    no_arr=self._args.no_arr,
                    no_str=self._args.no_str,
                    flow_style=self._args.flow_style,
                )
                + '---\n'
            )
        self._stream.flush()


def _field_path(field: str | None) -> list[str] | None:
    if field is None:
        return None
    parts = [part for part in field.split('.') if part]
    if not parts:
        raise CliError(f"invalid field value '{field}'")
    return parts


def run(args: argparse.Namespace) -> int:
    """Print messages until --once/--timeout is done, or until Ctrl-C."""
    from rclpy.executors import SingleThreadedExecutor

    printer = Printer(args)
    msg_class = get_message_class(args.message_type) if args.message_type else None
    if msg_class is not None and printer.field:
        check_field_path(msg_class, printer.field)

    with cli_node('topic_echo') as node:
        topic = expand_topic(node, args.topic_name)
        if msg_class is None:
            msg_class = get_message_class(resolve_topic_type(node, topic, args.discovery_timeout))
            if printer.field:
                check_field_path(msg_class, printer.field)
        qos = choose_qos(node, topic, args)
        node.create_subscription(msg_class, topic, printer, qos)
        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        deadline = None if args.timeout is None else time.monotonic() + args.timeout
        try:
            while not (args.once and printer.count):
                if deadline is not None and time.monotonic() >= deadline:
                    break
                executor.spin_once(timeout_sec=_SPIN_PERIOD_S)
        finally:
            executor.shutdown()
    if args.once and not printer.count:
        raise CliError(f"no message on '{topic}' within {args.timeout:g} s")
    return 0


def choose_qos(node, topic: str, args: argparse.Namespace):
    """The --qos-* profile; without single-policy overrides, adapted to the publishers."""
    profile = profile_from_args(args)
    if qos_overridden(args):
        return profile
    offered = [info.qos_profile for info in node.get_publishers_info_by_topic(topic)]
    profile, warnings = adapt_to_publishers(profile, offered)
    for warning in warnings:
        print(f'rmcli: warning: {warning}', file=sys.stderr)
    return profile
