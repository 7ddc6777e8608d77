"""The ``<node>: commands`` status on /diagnostics: commands the plugins refused.

A plugin refuses a command that is stale, stamped in the future or invalid (NaN, unknown
mode: :class:`rm_base.plugin.commands.CommandInput`) and logs it, throttled. The count
belongs on /diagnostics too, where a dashboard sees it without the log: one value per
plugin and topic, and WARN, with the newest reason, when a report period saw new ones.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus

from rm_base.plugin.commands import CommandInput
from rm_base.ros.diagnostics import diagnostic_status

#: The status's name after ``<node>: ``.
STATUS_NAME = 'commands'
#: Its value naming the topics with refusals since the last report (comma-separated).
NEW_KEY = 'rejected since the last report'


class CommandReport:
    """Builds the status; remembers the counts to say what changed since the last one.

    Args:
        node_name: prefix of the status name (``<node_name>: commands``).
    """

    def __init__(self, node_name: str) -> None:
        self._name = f'{node_name}: {STATUS_NAME}'
        self._last: dict[str, int] = {}

    def status(self, inputs: Iterable[tuple[str, CommandInput[Any]]]) -> DiagnosticStatus:
        """The status of the plugins' command inputs, as ``(plugin, input)`` pairs."""
        values: dict[str, object] = {}
        news = []
        topics = []
        counts = {}
        for plugin, command in inputs:
            key = f'{plugin} {command.topic}'
            count, reason = command.rejections()
            counts[key] = count
            values[f'{key} rejected'] = count
            new = count - self._last.get(key, 0)
            if new > 0:
                news.append(f'{new} on {command.topic} ({plugin}), the newest: {reason}')
                topics.append(command.topic)
        self._last = counts
        values[NEW_KEY] = ','.join(sorted(set(topics)))
        if news:
            level = DiagnosticStatus.WARN
            message = 'rejected since the last report: ' + '; '.join(news)
        else:
            level, message = DiagnosticStatus.OK, 'no command rejected since the last report'
        return diagnostic_status(self._name, level, message, 'commands', values)
