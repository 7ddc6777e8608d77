"""``rmcli service call``: call a service with a request given as YAML, like ``ros2 service call``.

It waits (bounded, ``--timeout``) for the service, sends one request and prints the
response as ros2cli does. Differences from ros2cli: integer fields accept the request's
constant names, and a service that does not answer in time is an error, not a hang.
"""

from __future__ import annotations

import argparse
import time

from .errors import CliError
from .interfaces import get_service_class
from .message_yaml import fill_message, parse_values
from .options import positive_float
from .ros_node import cli_node

DEFAULT_TIMEOUT_S = 10.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``service call``."""
    parser.add_argument(
        'service_name', help="Name of the ROS service (e.g. '/can_bridge/yaw/set_zero')"
    )
    parser.add_argument('service_type', help="Type of the service (e.g. 'std_srvs/srv/Trigger')")
    parser.add_argument(
        'values', nargs='?', default='{}',
        help="Values to fill the request with in YAML format (e.g. '{data: true}'), "
        'otherwise the request has default values',
    )
    parser.add_argument(
        '--timeout', type=positive_float, default=DEFAULT_TIMEOUT_S, metavar='S',
        help='Longest wait for the service and for its response [s] '
        f'(default: {DEFAULT_TIMEOUT_S:g})',
    )


def run(args: argparse.Namespace) -> int:
    """Call the service once and print its response."""
    srv_class = get_service_class(args.service_type)
    request = srv_class.Request()
    fill_message(request, parse_values(args.values))  # before ROS: fast, clear errors
    with cli_node('service_call') as node:
        client = node.create_client(srv_class, args.service_name)
        print('waiting for service to become available...', flush=True)
        if not client.wait_for_service(timeout_sec=args.timeout):
            raise CliError(f"service '{args.service_name}' is not available ({args.timeout:g} s)")
        print(f'requester: making request: {request!r}\n', flush=True)
        future = client.call_async(request)
        deadline = time.monotonic() + args.timeout
        from rclpy.executors import SingleThreadedExecutor

        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        try:
            while not future.done() and time.monotonic() < deadline:
                executor.spin_once(timeout_sec=0.1)
        finally:
            executor.remove_node(node)
            executor.shutdown()
        if not future.done():
            raise CliError(f"service '{args.service_name}' did not answer in {args.timeout:g} s")
        print(f'response:\n{future.result()!r}\n', flush=True)
    return 0
