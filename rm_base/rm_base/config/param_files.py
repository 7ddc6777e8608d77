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
