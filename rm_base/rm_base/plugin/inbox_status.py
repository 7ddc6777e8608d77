"""The ``<node>: inbox`` status on /diagnostics: what a loop's inbox took and dropped.

An inbox (:class:`rm_base.plugin.inbox.Inbox`) drops a topic's oldest message when the loop
has not handed out as many as the subscription's QoS depth; that is a command lost, so
it is reported, not only logged. Level: WARN when messages were dropped, could not be
taken or could not be handed to their callback since the previous report; OK otherwise.
"""

from __future__ import annotations

from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus

from rm_base.ros.diagnostics import diagnostic_status


class InboxReport:
    """Builds the inbox's status; remembers its counters to say what changed since.

    Args:
        node_name: prefix of the status name (``<node_name>: inbox``).
    """

    def __init__(self, node_name: str) -> None:
        self._name = f'{node_name}: inbox'
        self._last_dropped: dict[str, int] = {}
        self._last_lost: dict[str, int] = {}
        self._last_errors = 0
        self._last_receive_errors = 0

    def status(self, inbox: Any) -> DiagnosticStatus:
        """The status of inbox now (an Inbox; read from any thread)."""
        taken = dict(inbox.taken_by_topic)
        dropped = dict(inbox.dropped_by_topic)
        lost = dict(inbox.lost_by_topic)
        errors, receive_errors = inbox.errors, inbox.receive_errors
        problems = [
            f'{n} on {topic} dropped'
            for topic, count in sorted(dropped.items())
            if (n := count - self._last_dropped.get(topic, 0)) > 0
        ]
        problems += [
            f'{n} on {topic} lost before taken'
            for topic, count in sorted(lost.items())
            if (n := count - self._last_lost.get(topic, 0)) > 0
        ]
        self._last_lost = lost
        if receive_errors > self._last_receive_errors:
            problems.append(f'{receive_errors - self._last_receive_errors} take(s) failed')
        if errors > self._last_errors:
            problems.append(f'{errors - self._last_errors} not handed out (callback failed)')
        self._last_dropped = dropped
        self._last_errors, self._last_receive_errors = errors, receive_errors
        if problems:
            level = DiagnosticStatus.WARN
            message = 'since the last report: ' + ', '.join(problems)
        else:
            level, message = DiagnosticStatus.OK, 'ok'
        values: dict[str, Any] = {}
        for topic in sorted(taken):
            values[f'{topic} taken'] = taken[topic]
            values[f'{topic} dropped'] = dropped.get(topic, 0)
            values[f'{topic} lost'] = lost.get(topic, 0)
        values['pending'] = inbox.pending
        values['take errors'] = receive_errors
        values['callback errors'] = errors
        return diagnostic_status(self._name, level, message, 'inbox', values)
