"""``rmcli param``: list, get, set, describe, dump and load a node's parameters, as ros2 param.

Through the node's standard parameter services (rclpy's ``AsyncParameterClient``), so a set
takes the same path as ``ros2 param set`` and Foxglove's parameter panel: the node checks
it, applies it or says why not. Output is shaped like ros2param's. Each verb waits for the
node's services at most ``--timeout`` seconds (discovery of a new process takes one
announcement period of the others).
"""

from __future__ import annotations

import argparse
import difflib
import re
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import yaml
from rm_base.config.param_files import nest

from .errors import CliError
from .graph import Verb
from .options import positive_float
from .param_file import node_parameters
from .ros_node import cli_node

DEFAULT_TIMEOUT_S = 10.0

#: ParameterType constants -> ros2param's words (``Double value is: 0.5``).
_TYPE_WORDS = {
    1: 'Boolean', 2: 'Integer', 3: 'Double', 4: 'String', 5: 'Byte array',
    6: 'Boolean', 7: 'Integer', 8: 'Double', 9: 'String',
}
_TYPE_NAMES = {
    0: 'not set', 1: 'boolean', 2: 'integer', 3: 'double', 4: 'string', 5: 'byte array',
    6: 'boolean array', 7: 'integer array', 8: 'double array', 9: 'string array',
}


def _node_and_timeout(parser: argparse.ArgumentParser) -> None:
    parser.add_argument('node_name', help="Name of the ROS node (e.g. '/rm_robot')")
    parser.add_argument(
        '--timeout', type=positive_float, default=DEFAULT_TIMEOUT_S, metavar='S',
        help=f'Longest wait for the node and each answer [s] (default: {DEFAULT_TIMEOUT_S:g})',
    )


def add_list_arguments(parser: argparse.ArgumentParser) -> None:
    """``param list NODE [--filter PREFIX]``."""
    _node_and_timeout(parser)
    parser.add_argument(
        '--filter', default='', help='Only names that this regular expression matches '
        '(from their start, as ros2 param list)',
    )


def add_get_arguments(parser: argparse.ArgumentParser) -> None:
    """``param get NODE NAME``."""
    _node_and_timeout(parser)
    parser.add_argument('parameter_name', help='Name of the parameter')


def add_set_arguments(parser: argparse.ArgumentParser) -> None:
    """``param set NODE NAME VALUE``."""
    _node_and_timeout(parser)
    parser.add_argument('parameter_name', help='Name of the parameter')
    parser.add_argument('value', help='Value of the parameter, in YAML (e.g. 0.5, [1, 2])')


def add_describe_arguments(parser: argparse.ArgumentParser) -> None:
    """``param describe NODE NAME...``."""
    _node_and_timeout(parser)
    parser.add_argument('parameter_names', nargs='+', help='Names of the parameters')


def add_dump_arguments(parser: argparse.ArgumentParser) -> None:
    """``param dump NODE``."""
    _node_and_timeout(parser)


def add_load_arguments(parser: argparse.ArgumentParser) -> None:
    """``param load NODE FILE``."""
    _node_and_timeout(parser)
    parser.add_argument('parameter_file', type=Path, help='A parameter YAML file (param dump)')


def _call(node_name: str, timeout: float, work: Callable[[Any, Callable[[Any], Any]], int]) -> int:
    """Run work(client, wait) against the node's parameter services."""
    with cli_node('param') as node:
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.parameter_client import AsyncParameterClient

        client = AsyncParameterClient(node, node_name)
        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)

        def wait(future: Any) -> Any:
            deadline = time.monotonic() + timeout
            while not future.done() and time.monotonic() < deadline:
                executor.spin_once(timeout_sec=0.05)
            if not future.done():
                raise CliError(f'node {node_name} did not answer in {timeout:g} s')
            return future.result()

        try:
            deadline = time.monotonic() + timeout
            while not client.services_are_ready():
                if time.monotonic() > deadline:
                    raise CliError(f'node not found: {node_name} (waited {timeout:g} s)')
                executor.spin_once(timeout_sec=0.05)
            return work(client, wait)
        finally:
            executor.remove_node(node)
            executor.shutdown()


def _value(msg: Any) -> Any:
    from rclpy.parameter import parameter_value_to_python

    value = parameter_value_to_python(msg)
    return list(value) if isinstance(value, list | tuple) or hasattr(value, 'tolist') else value


def _names(client: Any, wait: Callable[[Any], Any], pattern: str = '') -> list[str]:
    try:
        match = re.compile(pattern).match
    except re.error as err:
        raise CliError(f'--filter {pattern!r} is not a regular expression: {err}') from None
    result = wait(client.list_parameters([], 0))
    return sorted(n for n in result.result.names if match(n))


def run_list(args: argparse.Namespace) -> int:
    """Print the node's parameter names, one per line, indented (as ros2 param list NODE)."""
    def work(client: Any, wait: Callable[[Any], Any]) -> int:
        for name in _names(client, wait, args.filter):
            print(f'  {name}')
        return 0

    return _call(args.node_name, args.timeout, work)


def run_get(args: argparse.Namespace) -> int:
    """Print one parameter's value (``Double value is: 0.5``)."""
    def work(client: Any, wait: Callable[[Any], Any]) -> int:
        values = wait(client.get_parameters([args.parameter_name])).values
        if not values or values[0].type == 0:
            raise CliError(f'Parameter not set: {args.parameter_name}')
        kind = values[0].type
        value = _value(values[0])
        verb = 'values are' if kind >= 5 else 'value is'
        print(f'{_TYPE_WORDS[kind]} {verb}: {value}')
        return 0

    return _call(args.node_name, args.timeout, work)


def _set(client: Any, wait: Callable[[Any], Any], parameters: Sequence[Any]) -> list[Any]:
    return list(wait(client.set_parameters(list(parameters))).results)


def run_set(args: argparse.Namespace) -> int:
    """Set one parameter; print the node's answer (exit 1 when it refuses)."""
    from rclpy.parameter import Parameter, get_parameter_value

    name = args.parameter_name
    value = get_parameter_value(args.value)  # YAML, as ros2 param set reads it

    def work(client: Any, wait: Callable[[Any], Any]) -> int:
        current = wait(client.get_parameters([name])).values
        wanted = _as_double(args.value, value) if current and current[0].type == 3 else value
        result = _set(client, wait, [Parameter.from_parameter_msg(_msg(name, wanted))])[0]
        if result.successful:
            print('Set parameter successful')
            return 0
        if not current:  # rclpy's reason for an undeclared name lists no names
            declared = _names(client, wait)
            close = difflib.get_close_matches(name, declared, n=3)
            hint = f' (did you mean {", ".join(close)}?)' if close else ''
            raise CliError(f'Setting parameter failed: {args.node_name} has no parameter '
                           f'{name}{hint}')
        raise CliError(f'Setting parameter failed: {result.reason}')

    return _call(args.node_name, args.timeout, work)


def _as_double(text: str, value: Any) -> Any:
    """The value for a double parameter: ``30`` and ``1e-3`` as the numbers they are.

    YAML (ros2 param set's reading) makes ``30`` an integer and ``1e-3`` a string, which a
    double parameter refuses as the wrong type; anything else is left as it was read.
    """
    from rcl_interfaces.msg import ParameterValue

    if value.type == 2:  # integer
        return ParameterValue(type=3, double_value=float(value.integer_value))
    if value.type == 4:  # string
        try:
            number = float(text)
        except ValueError:
            return value
        return ParameterValue(type=3, double_value=number)
    return value


def _msg(name: str, value: Any) -> Any:
    from rcl_interfaces.msg import Parameter as ParameterMsg

    return ParameterMsg(name=name, value=value)


def run_describe(args: argparse.Namespace) -> int:
    """Print each parameter's descriptor (as ros2 param describe)."""
    def work(client: Any, wait: Callable[[Any], Any]) -> int:
        descriptors = wait(client.describe_parameters(args.parameter_names)).descriptors
        for name, d in zip(args.parameter_names, descriptors, strict=True):
            print(f'Parameter name: {name}')
            print(f'  Type: {_TYPE_NAMES.get(d.type, d.type)}')
            if d.description:
                print(f'  Description: {d.description}')
            print('  Constraints:')
            if d.read_only:
                print('    Read only: true')
            if d.additional_constraints:
                print(f'    Additional constraints: {d.additional_constraints}')
        return 0

    return _call(args.node_name, args.timeout, work)


def run_dump(args: argparse.Namespace) -> int:
    """Print every parameter as a parameter file (``<node>: ros__parameters: ...``)."""
    def work(client: Any, wait: Callable[[Any], Any]) -> int:
        names = _names(client, wait)
        values = wait(client.get_parameters(names)).values
        # not set: a parameter file cannot say "unset"
        tree = nest({name: _value(value) for name, value in zip(names, values, strict=True)
                     if value.type != 0})
        node = args.node_name if args.node_name.startswith('/') else '/' + args.node_name
        print(yaml.safe_dump({node: {'ros__parameters': tree}}, sort_keys=True), end='')
        return 0

    return _call(args.node_name, args.timeout, work)


def run_load(args: argparse.Namespace) -> int:
    """Set each parameter of the file's section that differs, one at a time (as ros2 does).

    Values equal to the node's are left alone, so a dump of the node loads back whole
    (its read-only values included); exit 1 if the node refused one.
    """
    from rclpy.parameter import Parameter

    path = args.parameter_file
    if not path.is_file():
        raise CliError(f'no parameter file {path}')
    node = args.node_name if args.node_name.startswith('/') else '/' + args.node_name
    try:
        document = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as err:
        raise CliError(f'{path}: {_yaml_problem(err)}') from None
    parameters = {}
    for name, value in node_parameters(document, node, str(path)).items():
        if value is None:  # 'key:' with nothing after it: a file cannot unset a parameter
            raise CliError(f'{path}: {name} has no value')
        try:
            parameters[name] = Parameter(name, value=value)
        except TypeError as err:  # e.g. a list mixing types: no parameter type holds it
            raise CliError(f'{path}: {name}: {err}') from None

    def work(client: Any, wait: Callable[[Any], Any]) -> int:
        failed = 0
        # only declared names: one undeclared name makes the node answer with no values
        declared = sorted(set(parameters) & set(_names(client, wait)))
        current = dict(zip(declared, wait(client.get_parameters(declared)).values, strict=True))
        for name, parameter in parameters.items():
            wanted = parameter.get_parameter_value()
            if name in current and current[name].type == 3:  # as set reads a double
                wanted = _as_double(str(parameter.value), wanted)
            if name in current and _value(current[name]) == _value(wanted):
                continue  # no change: a dump loads back even with its read-only values
            result = _set(client, wait, [Parameter.from_parameter_msg(_msg(name, wanted))])[0]
            if result.successful:
                print(f'Set parameter {name} successful')
            else:
                failed += 1
                # rclpy's own reason for an undeclared name lists no names
                reason = result.reason if name in current else f'{node} has no such parameter'
                print(f'Set parameter {name} failed: {reason}')
        return 1 if failed else 0

    return _call(args.node_name, args.timeout, work)


def _yaml_problem(err: Exception) -> str:
    """One line for why a file did not read as YAML: where, and what PyYAML found."""
    mark = getattr(err, 'problem_mark', None)
    problem = getattr(err, 'problem', None)
    if mark is None or problem is None:
        return f'not a YAML file: {" ".join(str(err).split())}'
    return f'line {mark.line + 1}, column {mark.column + 1}: not YAML: {problem}'


VERBS = {
    'describe': (Verb(add_describe_arguments, run_describe), 'Show descriptive information '
                 'about declared parameters'),
    'dump': (Verb(add_dump_arguments, run_dump), 'Show all of the parameters of a node in a '
             'YAML file format'),
    'get': (Verb(add_get_arguments, run_get), 'Get parameter'),
    'list': (Verb(add_list_arguments, run_list), 'Output a list of available parameters'),
    'load': (Verb(add_load_arguments, run_load), 'Load parameter file for a node'),
    'set': (Verb(add_set_arguments, run_set), 'Set parameter'),
}
"""``rmcli param <verb>``: the verb, and its one-line help (ros2param's)."""
