"""``rmcli node list|info``, ``topic info|type``, ``service list|type``, ``interface show``.

What ros2cli prints for each, read from this process's view of the graph. There is no
daemon: every call waits until discovery has settled (:func:`settled`: a second without a
new name, five at most), so a new process does not print half a graph.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .errors import CliError
from .options import nonnegative_float
from .ros_node import cli_node, expand_topic
from .topic_list import DEFAULT_SPIN_TIME_S, settled


def _spin_time(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        '--spin-time', type=nonnegative_float, default=DEFAULT_SPIN_TIME_S,
        help='Shortest wait for discovery [s]; the graph is read once it has settled',
    )


def _hidden(name: str) -> bool:
    return any(part.startswith('_') for part in name.split('/') if part)


def _full(name: str, namespace: str) -> str:
    return f'{namespace.rstrip("/")}/{name}'


def _nodes(node: Any) -> list[str]:
    return sorted(_full(n, ns) for n, ns in node.get_node_names_and_namespaces())


def _graph(node: Any, spin_time: float) -> None:
    """Wait until the graph has settled (topics as the measure, as topic list does)."""
    settled(node.get_topic_names_and_types, spin_time)


# -- node ------------------------------------------------------------------------------------

def add_node_list_arguments(parser: argparse.ArgumentParser) -> None:
    """``node list [-a] [-c]``."""
    parser.add_argument(
        '-a', '--all', action='store_true', help='Display all nodes even hidden ones'
    )
    parser.add_argument('-c', '--count-nodes', action='store_true',
                        help='Only display the number of nodes discovered')
    _spin_time(parser)


def run_node_list(args: argparse.Namespace) -> int:
    """Print the nodes' full names, sorted."""
    with cli_node('node_list') as node:
        _graph(node, args.spin_time)
        names = [n for n in _nodes(node) if args.all or not _hidden(n)]
    if args.count_nodes:
        print(len(names))
    else:
        print(*names, sep='\n')
    return 0


def add_node_info_arguments(parser: argparse.ArgumentParser) -> None:
    """``node info NODE``."""
    parser.add_argument('node_name', help='Node name to request information')
    parser.add_argument('--include-hidden', action='store_true',
                        help='Display hidden topics, services, and actions as well')
    _spin_time(parser)


def run_node_info(args: argparse.Namespace) -> int:
    """Print a node's subscribers, publishers, service servers and clients."""
    name = args.node_name if args.node_name.startswith('/') else '/' + args.node_name
    with cli_node('node_info') as node:
        _graph(node, args.spin_time)
        if name not in _nodes(node):
            raise CliError(f'Unable to find node {args.node_name!r}')
        namespace, _, short = name.rpartition('/')
        namespace = namespace or '/'
        sections: list[tuple[str, Callable[..., Any]]] = [
            ('Subscribers', node.get_subscriber_names_and_types_by_node),
            ('Publishers', node.get_publisher_names_and_types_by_node),
            ('Service Servers', node.get_service_names_and_types_by_node),
            ('Service Clients', node.get_client_names_and_types_by_node),
        ]
        lines = [name]
        for title, query in sections:
            lines.append(f'  {title}:')
            for topic, types in sorted(query(short, namespace)):
                if args.include_hidden or not _hidden(topic):
                    lines.append(f'    {topic}: {", ".join(types)}')
        lines += ['  Action Servers:', '', '  Action Clients:', '']
    print('\n'.join(lines))
    return 0


# -- topic -----------------------------------------------------------------------------------

def add_topic_info_arguments(parser: argparse.ArgumentParser) -> None:
    """``topic info TOPIC [-v]``."""
    parser.add_argument('topic_name', help="Name of the ROS topic to get info (e.g. '/chatter')")
    parser.add_argument('-v', '--verbose', action='store_true',
                        help='Prints detailed information like the node name, node namespace, '
                        'topic type, GUID and QoS Profile of the publishers and subscribers '
                        'to this topic')
    _spin_time(parser)


def run_topic_info(args: argparse.Namespace) -> int:
    """Print a topic's type and endpoint counts; with -v each endpoint and its QoS."""
    with cli_node('topic_info') as node:
        topic = expand_topic(node, args.topic_name)
        _graph(node, args.spin_time)
        types = dict(node.get_topic_names_and_types()).get(topic)
        if not types:
            raise CliError(f"Unknown topic '{topic}'")
        publishers = node.get_publishers_info_by_topic(topic)
        subscribers = node.get_subscriptions_info_by_topic(topic)
    lines = [f'Type: {"; ".join(types)}']
    for title, endpoints in (('Publisher', publishers), ('Subscription', subscribers)):
        if args.verbose:
            lines += ['', f'{title} count: {len(endpoints)}', '']
            lines += [f'{endpoint}\n' for endpoint in endpoints]
        else:
            lines.append(f'{title} count: {len(endpoints)}')
    print('\n'.join(lines))
    return 0


def add_topic_type_arguments(parser: argparse.ArgumentParser) -> None:
    """``topic type TOPIC``."""
    parser.add_argument('topic_name', help="Name of the ROS topic to get type (e.g. '/chatter')")
    _spin_time(parser)


def run_topic_type(args: argparse.Namespace) -> int:
    """Print a topic's type(s), one per line."""
    with cli_node('topic_type') as node:
        topic = expand_topic(node, args.topic_name)
        _graph(node, args.spin_time)
        types = dict(node.get_topic_names_and_types()).get(topic)
    if not types:
        raise CliError(f"Unknown topic '{topic}'")
    print(*types, sep='\n')
    return 0


# -- service ---------------------------------------------------------------------------------

def add_service_list_arguments(parser: argparse.ArgumentParser) -> None:
    """``service list [-t] [-c]``."""
    parser.add_argument('-t', '--show-types', action='store_true',
                        help='Additionally show the service type')
    parser.add_argument('-c', '--count-services', action='store_true',
                        help='Only display the number of services discovered')
    parser.add_argument('--include-hidden-services', action='store_true',
                        help='Consider hidden services as well')
    _spin_time(parser)


def _services(node: Any, spin_time: float) -> list[tuple[str, list[str]]]:
    # services settle as the topics do: they come with the same announcements
    _graph(node, spin_time)
    return sorted((n, list(t)) for n, t in node.get_service_names_and_types())


def run_service_list(args: argparse.Namespace) -> int:
    """Print the services on the graph."""
    with cli_node('service_list') as node:
        services = [
            (name, types) for name, types in _services(node, args.spin_time)
            if args.include_hidden_services or not _hidden(name)
        ]
    if args.count_services:
        print(len(services))
    for name, types in [] if args.count_services else services:
        print(f'{name} [{", ".join(types)}]' if args.show_types else name)
    return 0


def add_service_type_arguments(parser: argparse.ArgumentParser) -> None:
    """``service type SERVICE``."""
    parser.add_argument(
        'service_name', help="Name of the ROS service (e.g. '/rm_robot/enable_all')"
    )
    _spin_time(parser)


def run_service_type(args: argparse.Namespace) -> int:
    """Print a service's type."""
    with cli_node('service_type') as node:
        types = dict(_services(node, args.spin_time)).get(args.service_name)
    if not types:
        raise CliError(f"Unknown service '{args.service_name}'")
    print(*types, sep='\n')
    return 0


# -- interface -------------------------------------------------------------------------------

def add_interface_show_arguments(parser: argparse.ArgumentParser) -> None:
    """``interface show TYPE``."""
    parser.add_argument('type', help="Show an interface definition (e.g. 'rm_msgs/msg/ChassisCmd')")


def interface_file(type_name: str) -> Path:
    """The installed definition file of ``pkg/msg/Name`` or ``pkg/srv/Name``.

    Raises:
        CliError: not an interface name, or no such package or file in the ament index.
    """
    from ament_index_python.packages import PackageNotFoundError, get_package_share_directory

    parts = type_name.split('/')
    if len(parts) == 2:  # pkg/Name: a message, as ros2 takes it
        parts.insert(1, 'msg')
    if len(parts) != 3 or parts[1] not in ('msg', 'srv') or not all(parts):
        raise CliError(f"'{type_name}' is not an interface name (pkg/msg/Name, pkg/srv/Name)")
    package, kind, name = parts
    try:
        share = Path(get_package_share_directory(package))
    except (PackageNotFoundError, ValueError):
        raise CliError(f"Unknown package '{package}'") from None
    path = share / kind / f'{name}.{kind}'
    if not path.is_file():
        raise CliError(f"Could not find the interface '{path}'")
    return path


def run_interface_show(args: argparse.Namespace) -> int:
    """Print the interface's definition as installed (comments and constants included)."""
    print(interface_file(args.type).read_text(), end='')
    return 0


class Verb:
    """One verb as the rmcli parser takes it (``add_arguments``, ``run``)."""

    def __init__(
        self,
        add_arguments: Callable[[argparse.ArgumentParser], None],
        run: Callable[[argparse.Namespace], int],
    ) -> None:
        self.add_arguments = add_arguments
        self.run = run


NODE_VERBS = {
    'info': (Verb(add_node_info_arguments, run_node_info), 'Output information about a node'),
    'list': (Verb(add_node_list_arguments, run_node_list), 'Output a list of available nodes'),
}
TOPIC_VERBS = {
    'info': (Verb(add_topic_info_arguments, run_topic_info), 'Print information about a topic'),
    'type': (Verb(add_topic_type_arguments, run_topic_type), "Print a topic's type"),
}
SERVICE_VERBS = {
    'list': (Verb(add_service_list_arguments, run_service_list),
             'Output a list of available services'),
    'type': (Verb(add_service_type_arguments, run_service_type), "Output a service's type"),
}
INTERFACE_VERBS = {
    'show': (Verb(add_interface_show_arguments, run_interface_show),
             'Output the interface definition'),
}
