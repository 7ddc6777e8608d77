"""ROS 2 parameter files read without rcl: ``{node: {'a.b.c': value}}``, as rcl reads them.

For the tools that need a robot config outside a node (the rm_sim process, tests, bench):
each top-level key is a node, its ``ros__parameters`` are nested keys joined with ``.``,
and a later file overrides an earlier one key by key. No rclpy here.
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


def load_parameters(files: Iterable[str | Path]) -> dict[str, dict[str, Any]]:
    """{node name: flat parameters} of the files, later files overriding.

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
