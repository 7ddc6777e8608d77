"""The keys of a host's parameter files that nothing read: a typo, or a plugin not loaded.

rclpy keeps a parameter file's values for names nobody declares and says nothing, so
``shooter.max_hzz: 3.0`` would start the robot with the default rate. After every plugin
has read its keys, the host asks :func:`unread_keys` which were left; a key of a loaded
plugin or of the host itself is an error (with the nearest declared name), while the
sections of plugins the ``plugins`` list leaves out (a robot file's ``ui:`` under a
simulation overlay) are only named. No rclpy here.
"""

from __future__ import annotations

import difflib
from collections.abc import Collection, Iterable
from dataclasses import dataclass


@dataclass(frozen=True)
class UnreadKeys:
    """What :func:`unread_keys` found.

    Attributes:
        unknown: keys that belong to the host or a loaded plugin but name no parameter.
        idle_plugins: sections of plugin configs (a ``<name>.type`` key) not in the plugin
            list, whose keys are not read.
    """

    unknown: tuple[str, ...]
    idle_plugins: tuple[str, ...]


def unread_keys(
    given: Iterable[str], declared: Collection[str], plugins: Collection[str]
) -> UnreadKeys:
    """Sort the given keys that were not declared.

    Args:
        given: the parameter names the node's files (and overrides) hold.
        declared: the names the node declared.
        plugins: the instance names of the loaded plugins.
    """
    given = set(given)
    configs = {name.split('.', 1)[0] for name in given if name.count('.') == 1
               and name.endswith('.type')}
    idle = configs - set(plugins)
    unknown = sorted(
        name for name in given - set(declared) if name.split('.', 1)[0] not in idle
    )
    return UnreadKeys(tuple(unknown), tuple(sorted(idle)))


def unknown_keys_error(node: str, unknown: Collection[str], declared: Collection[str]) -> str:
    """One message for the unknown keys, each with the declared name nearest to it."""
    said = []
    for key in sorted(unknown):
        close = difflib.get_close_matches(key, list(declared), n=1)
        said.append(f'{key!r} (did you mean {close[0]!r}?)' if close else repr(key))
    return (
        f'{node}: unknown parameter(s) {", ".join(said)}: no plugin of the robot and not the '
        'node itself reads them (docs/PARAMETERS.md lists every key)'
    )
