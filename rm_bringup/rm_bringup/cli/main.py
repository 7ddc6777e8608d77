"""``rmcli``: the project's thin, faithful stand-in for ros2cli's everyday commands.

topic, service, param, node, interface and bag, and teleop: ros2cli and rosbag2 are not on PyPI, so
the virtualenv has this instead. Exit codes: 0 ok
(also when stopped with Ctrl-C, the normal way to end echo/hz/record), 1 a runtime error
(one line on stderr), 2 a usage error.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from typing import Any

from . import (
    bag_info,
    bag_play,
    bag_plot,
    bag_record,
    bag_reindex,
    graph,
    param,
    service_call,
    teleop,
    topic_bw,
    topic_echo,
    topic_hz,
    topic_list,
    topic_pub,
    tune_step,
)
from .errors import CliError, UsageError

PROG = 'rmcli'

# group -> verb -> (module with add_arguments(parser) and run(args), one-line help)
VERBS: dict[str, dict[str, tuple[Any, str]]] = {
    'topic': {
        'bw': (topic_bw, 'Display bandwidth used by topic'),
        'echo': (topic_echo, 'Output messages from a topic'),
        'hz': (topic_hz, 'Print the average receiving rate to screen'),
        'list': (topic_list, 'Output a list of available topics'),
        'pub': (topic_pub, 'Publish a message to a topic'),
        **graph.TOPIC_VERBS,
    },
    'service': {
        'call': (service_call, 'Call a service'),
        **graph.SERVICE_VERBS,
    },
    'param': param.VERBS,
    'node': graph.NODE_VERBS,
    'interface': graph.INTERFACE_VERBS,
    'tune': {
        'step': (tune_step, 'Step one joint; print rise time, overshoot, settling time and '
                 'steady-state error; plot it'),
    },
    'bag': {
        'info': (bag_info, 'Print information about a bag to the screen'),
        'play': (bag_play, 'Play back ROS data from a bag'),
        'plot': (bag_plot, 'Plot chassis, gimbal and shooter data of a bag to PNG files'),
        'record': (bag_record, 'Record ROS data to a bag'),
        'reindex': (bag_reindex, "Rebuild a killed recording's end and metadata.yaml"),
    },
}
# commands without verbs: name -> (module, one-line help)
TOOLS: dict[str, tuple[Any, str]] = {
    'teleop': (teleop, "Drive the robot from the keyboard, as the operator's remote does"),
}
GROUP_HELP = {
    'topic': 'Various topic related sub-commands',
    'service': 'Various service related sub-commands',
    'param': 'Various param related sub-commands',
    'node': 'Various node related sub-commands',
    'interface': 'Show information about ROS interfaces',
    'tune': 'Tuning aids',
    'bag': 'Various rosbag related sub-commands',
}


def build_parser() -> argparse.ArgumentParser:
    """Return the parser of every group and verb."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description='rm_ros2 command-line tool: ros2 topic, service, param, node, interface '
        'and bag, without ros2cli.',
        epilog=f'Call `{PROG} <command> -h` for more detailed usage.',
    )
    parser.set_defaults(help_parser=parser)
    groups = parser.add_subparsers(title='Commands', metavar='Command')
    for group, verbs in VERBS.items():
        group_parser = groups.add_parser(group, help=GROUP_HELP[group])
        group_parser.set_defaults(help_parser=group_parser)
        verb_parsers = group_parser.add_subparsers(title='Commands', metavar='Command')
        for verb, (module, help_text) in verbs.items():
            verb_parser = verb_parsers.add_parser(verb, help=help_text, description=f'{help_text}.')
            module.add_arguments(verb_parser)
            verb_parser.set_defaults(run=module.run, help_parser=verb_parser)
    for name, (module, help_text) in TOOLS.items():
        tool_parser = groups.add_parser(name, help=help_text, description=f'{help_text}.')
        module.add_arguments(tool_parser)
        tool_parser.set_defaults(run=module.run, help_parser=tool_parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run one rmcli command; return its exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)  # exits with 2 on a usage error
    if not hasattr(args, 'run'):
        args.help_parser.print_help()
        return 0
    try:
        return args.run(args) or 0
    except UsageError as err:
        args.help_parser.print_usage(sys.stderr)
        print(f'{args.help_parser.prog}: error: {err}', file=sys.stderr)
        return 2
    except CliError as err:
        print(f'{PROG}: error: {err}', file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 0
    except BrokenPipeError:
        # `rmcli topic echo ... | head`: the reader left; exit quietly, like other tools.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == '__main__':
    sys.exit(main())
