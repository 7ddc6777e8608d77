"""rm_robot's command sources from its parameters (``command_sources``, ``command_source.*``).

The arbitration itself is :mod:`rm_base.plugin.command_mux`; this reads which commanders a
robot has. By default: ``manual`` (rm_manual's ``/manual/*`` topics, priority 100, 0.2 s)
above ``external`` (the plain topics, priority 10, 0.5 s). An empty list turns the
arbitration off: every plugin then takes its plain topic from anyone.
"""

from __future__ import annotations

from rm_base.plugin import PluginParams
from rm_base.plugin.command_mux import DEFAULT_SOURCES, CommandSource, check_sources
from rm_base.plugin.errors import ParameterError

_DEFAULTS = {s.name: s for s in DEFAULT_SOURCES}


def read_command_sources(params: PluginParams) -> tuple[CommandSource, ...]:
    """Declare and read the command sources (node-level parameters), highest priority first.

    Raises:
        ParameterError: a key is missing or out of range, or two sources clash.
    """
    names = params.string_array(
        'command_sources', [s.name for s in DEFAULT_SOURCES], unique=True,
        description='the commanders arbitrated on every command topic (the twist_mux '
                    "pattern; see command_source.<name>.*); [''] turns arbitration off",
    )
    sources = []
    for name in (n for n in names if n):
        default = _DEFAULTS.get(name)
        group = params.group(f'command_source.{name}')
        namespace = group.string(
            'namespace', *((default.namespace,) if default else ()),
            description="namespace its topics are under ('' = the plain /chassis_cmd...)",
        )
        priority = group.integer(
            'priority', *((default.priority,) if default else ()), ge=0, le=1000,
            description='higher wins while the source is live',
        )
        timeout = group.double(
            'timeout', *((default.timeout,) if default else ()), unit='s', gt=0.0, le=60.0,
            description='the source holds a topic this long after its last message on it',
        )
        try:
            sources.append(CommandSource(name, namespace.rstrip('/'), priority, timeout))
        except ValueError as err:
            raise ParameterError(str(err), key=f'command_source.{name}') from None
    try:
        return check_sources(sources)
    except ValueError as err:
        raise ParameterError(str(err), key='command_sources') from None
