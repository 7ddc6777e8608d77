"""ROS 2 parameter files read without rcl: ``{node: {'a.b.c': value}}``, as rcl reads them.

For the tools that need a robot config outside a node (the rm_sim process, rmcli, tests,
bench): each top-level key is a section (a node's name, or ``/**`` for every node), its
``ros__parameters`` are nested keys joined with ``.``, and a later file overrides an
earlier one key by key. A node takes its relative name's section, its absolute name's and
the wildcard's, merged as rcl merges them (:func:`parameters_for`). No rclpy here.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import yaml

from rm_base.errors import ConfigError


def flatten(tree: Mapping[str, Any], prefix: str = '') -> dict[str, Any]:
    """Nested parameters -> {'a.b.c': value}."""
    flat: dict[str, Any] = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, Mapping):
            flat.update(flatten(value, f'{name}.'))
        else:
            flat[name] = value
    return flat


def nest(flat: Mapping[str, Any]) -> dict[str, Any]:
    """{'a.b.c': value} -> nested parameters, as a parameter file writes them.

    A name that is a parameter and a group at once (can_bridge's ``sim`` and
    ``sim.timing``) cannot be one YAML key: its members keep dotted keys beside it
    (``sim.timing:``), which rcl reads as the same names. :func:`flatten` undoes it.
    """
    tree: dict[str, Any] = {}
    groups: dict[str, dict[str, Any]] = {}
    for name, value in flat.items():
        head, dot, rest = name.partition('.')
        if dot:
            groups.setdefault(head, {})[rest] = value
        else:
            tree[head] = value
    for head, members in groups.items():
        inner = nest(members)
        if head in tree:
            tree.update({f'{head}.{key}': value for key, value in inner.items()})
        else:
            tree[head] = inner
    return tree


#: The section that holds parameters for every node.
WILDCARD = '/**'


def section_names(node: str) -> tuple[str, ...]:
    """The sections of a parameter file that hold node's parameters (``/rm_robot``)."""
    relative = node.lstrip('/')
    return (WILDCARD, relative, f'/{relative}')


def parameters_for(sections: Mapping[str, Mapping[str, Any]], node: str) -> dict[str, Any]:
    """{parameter: value} that the sections give node, as rcl merges them.

    Args:
        sections: ``{section name: flat parameters}``, in the order the names first
            appeared in the files (:func:`load_parameters` keeps it).
        node: the node's name (``can_bridge`` or ``/can_bridge``).

    rcl keeps one entry per section name, which later files update, and applies a node's
    entries in that order: a dump's ``/can_bridge:`` after the config's ``can_bridge:``
    wins whatever the order of the files.
    """
    names = section_names(node)
    merged: dict[str, Any] = {}
    for name, values in sections.items():
        if name in names:
            merged.update(values)
    return merged


def load_parameters(files: Iterable[str | Path]) -> dict[str, dict[str, Any]]:
    """{section name: flat parameters} of the files, later files overriding.

    The sections come in the order their names first appeared (see :func:`parameters_for`).

    Raises:
        ConfigError: a file is missing, not YAML, or not a mapping of nodes.
    """
    nodes: dict[str, dict[str, Any]] = {}
    for path in files:
        try:
            document = yaml.safe_load(Path(path).read_text()) or {}
        except (OSError, yaml.YAMLError) as err:
            raise ConfigError(f'{path}: {err}') from err
        if not isinstance(document, Mapping):
            raise ConfigError(f'{path}: not a ROS parameter file (a mapping of nodes)')
        for node, section in document.items():
            params = (section or {}).get('ros__parameters', {})
            nodes.setdefault(node, {}).update(flatten(params))
    return nodes
