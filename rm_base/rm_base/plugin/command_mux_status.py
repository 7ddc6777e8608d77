"""The ``<node>: command sources`` status on /diagnostics: who is in charge of each topic.

Level: always OK (who commands is news, not a fault; a silent robot is the commands'
timeouts' business). Values name the source in charge of each topic ('' when all are
silent) and what each source had taken and yielded.
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus

from rm_base.plugin.command_mux import CommandMux
from rm_base.ros.diagnostics import diagnostic_status

#: The status's name after ``<node>: ``.
STATUS_NAME = 'command sources'


def command_sources_status(node_name: str, mux: CommandMux, now_ns: int) -> DiagnosticStatus:
    """The status of mux at now_ns (any thread)."""
    report = mux.report(now_ns)
    values: dict[str, object] = {}
    charge = []
    for topic, entry in report.items():
        values[f'{topic} in charge'] = entry['in_charge']
        charge.append(f"{topic} {entry['in_charge'] or '-'}")
        for source in mux.sources:
            values[f'{topic} {source.name} taken'] = entry['taken'][source.name]
            values[f'{topic} {source.name} yielded'] = entry['yielded'][source.name]
    values['sources'] = ', '.join(
        f'{s.name} ({s.namespace or "/"}, priority {s.priority}, {s.timeout:g} s)'
        for s in mux.sources
    )
    values['switches'] = mux.switches
    message = 'in charge: ' + (', '.join(charge) if charge else 'no command topic')
    return diagnostic_status(f'{node_name}: {STATUS_NAME}', DiagnosticStatus.OK, message,
                             'command_mux', values)
