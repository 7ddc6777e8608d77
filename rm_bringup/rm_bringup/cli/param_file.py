"""The section of a ROS 2 parameter file that is for one node, as rcl picks it.

``ros2 param load`` only takes a section keyed by the node's absolute name (``/rm_robot:``),
while rcl, reading the same file at start-up, also takes the relative name (``rm_robot:``,
as rm_bringup/config/ writes it) and the wildcard ``/**``. rmcli takes what rcl takes, so
a robot's own config loads into the running node. No rclpy here.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.config.param_files import WILDCARD, flatten, parameters_for, section_names

from .errors import CliError


def node_parameters(document: Any, node: str, source: str) -> dict[str, Any]:
    """{parameter name: value} that a parameter file gives node, as rcl merges its sections.

    Args:
        document: the file as YAML loaded it.
        node: the node's absolute name.
        source: the file's name, for errors.

    Raises:
        CliError: the file is not a mapping of nodes, has no section for node, or a section
            without ``ros__parameters``.
    """
    if not isinstance(document, Mapping):
        raise CliError(f'{source}: not a ROS parameter file (a mapping of node names)')
    names = section_names(node)
    sections: dict[str, dict[str, Any]] = {}
    for key, section in document.items():
        if key not in names:
            continue
        if not isinstance(section, Mapping) or not isinstance(
            section.get('ros__parameters'), Mapping
        ):
            raise CliError(f"{source}: '{key}' has no 'ros__parameters' mapping")
        sections[key] = flatten(section['ros__parameters'])
    if not sections:
        nodes = ', '.join(str(k) for k in document) or 'none'
        raise CliError(
            f'{source}: no parameters for {node} (keys {node.lstrip("/")}, {node} or '
            f'{WILDCARD}); the file has: {nodes}'
        )
    return parameters_for(sections, node)
