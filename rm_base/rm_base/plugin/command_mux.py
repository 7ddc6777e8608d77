"""Command arbitration: several commanders, one command per topic, by priority (twist_mux).

Every command topic a plugin subscribes (``PluginBase.subscribe_command``: /chassis_cmd,
/vel_cmd, /gimbal_cmd, /shoot_cmd...) is fed by several *sources*. A source is a namespace
its commander publishes under (``/manual`` for rm_manual: ``/manual/chassis_cmd``; ``''``
for the plain topics that ``topic pub``, a replay or a planner use), a priority and a
timeout. Per topic, the source in charge is the live source of highest priority, live
meaning its last message on that topic came within its timeout; only its messages reach the
plugin, the others are counted as yielded. A source that falls silent yields once its
timeout has passed; nothing has to publish to hold the others off, and an operator's
explicit PASSIVE wins over every lower source because it is a command like any other.

Pure: no rclpy; the caller hands in receive times [ns] and does the logging.
"""

from __future__ import annotations

import dataclasses
import re
import threading
from collections.abc import Callable, Sequence
from typing import Any

_NS_PER_S = 1_000_000_000
_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*')


@dataclasses.dataclass(frozen=True)
class CommandSource:
    """One commander of the robot.

    Attributes:
        name: what logs, /diagnostics and the status line call it.
        namespace: the namespace its topics are under ('' for the plain topics); absolute.
        priority: higher wins while live.
        timeout: seconds after its last message on a topic that it still holds that topic.
    """

    name: str
    namespace: str
    priority: int
    timeout: float

    def __post_init__(self) -> None:
        if not _NAME.fullmatch(self.name):
            raise ValueError(f'command source name {self.name!r}: a letter, then letters, '
                             'digits or _')
        if self.namespace and (not self.namespace.startswith('/')
                               or self.namespace.endswith('/')):
            raise ValueError(f'command source {self.name}: namespace {self.namespace!r} must '
                             "be '' or absolute without a trailing '/' (e.g. /manual)")
        if not 0.0 < self.timeout <= 60.0:
            raise ValueError(f'command source {self.name}: timeout {self.timeout!r} s must be '
                             'in (0, 60]')

    def topic(self, topic: str) -> str:
        """This source's name of an absolute topic (``/chassis_cmd`` -> ``/manual/chassis_cmd``)."""
        return f'{self.namespace}{topic}'


#: The robot's sources unless its config names others: the operator above everyone else.
DEFAULT_SOURCES = (
    CommandSource('manual', '/manual', 100, 0.2),
    CommandSource('external', '', 10, 0.5),
)


def check_sources(sources: Sequence[CommandSource]) -> tuple[CommandSource, ...]:
    """The sources, highest priority first.

    Raises:
        ValueError: two sources share a name, a namespace or a priority.
    """
    for attr in ('name', 'namespace', 'priority'):
        values = [getattr(s, attr) for s in sources]
        dup = next((v for v in values if values.count(v) > 1), None)
        if dup is not None:
            raise ValueError(f'two command sources have the {attr} {dup!r}')
    return tuple(sorted(sources, key=lambda s: -s.priority))


class _Topic:
    """Arbitration of one topic: each source's last message time, the source in charge."""

    def __init__(self, sources: tuple[CommandSource, ...]) -> None:
        self.last_ns: dict[str, int] = {}
        self.in_charge: CommandSource | None = None
        self.taken = dict.fromkeys((s.name for s in sources), 0)
        self.yielded = dict.fromkeys((s.name for s in sources), 0)


class CommandMux:
    """Chooses, per command topic, whose messages reach the plugins (see the module doc).

    Args:
        sources: the commanders; at least one.
        on_switch: called with ``(topic, old, new, why)`` when a topic's source in charge
            changes (names; ``''`` for none), for the log.

    Raises:
        ValueError: no source, or two that clash (:func:`check_sources`).
    """

    def __init__(
        self,
        sources: Sequence[CommandSource],
        on_switch: Callable[[str, str, str, str], Any] | None = None,
    ) -> None:
        if not sources:
            raise ValueError('at least one command source is needed')
        self.sources = check_sources(sources)
        self._on_switch = on_switch
        self._lock = threading.Lock()
        self._topics: dict[str, _Topic] = {}
        self.switches = 0

    @property
    def topics(self) -> tuple[str, ...]:
        """The topics arbitrated, sorted (none on a node whose plugins take no command)."""
        with self._lock:
            return tuple(sorted(self._topics))

    def add_topic(self, topic: str) -> list[tuple[CommandSource, str]]:
        """Arbitrate an absolute topic; return each source with the topic it publishes on."""
        with self._lock:
            self._topics.setdefault(topic, _Topic(self.sources))
        return [(s, s.topic(topic)) for s in self.sources]

    def offer(self, topic: str, source: CommandSource, receive_ns: int) -> bool:
        """A message of source on topic came at receive_ns: whether it reaches the plugin."""
        with self._lock:
            t = self._topics[topic]
            t.last_ns[source.name] = receive_ns
            chosen = self._choose(t, receive_ns)
            passes = chosen is source
            counts = t.taken if passes else t.yielded
            counts[source.name] += 1
            switch = self._note(topic, t, chosen, receive_ns)
        if switch is not None and self._on_switch is not None:
            self._on_switch(*switch)
        return passes

    def in_charge(self, topic: str, now_ns: int) -> CommandSource | None:
        """The source in charge of topic at now_ns (None: every source silent)."""
        with self._lock:
            t = self._topics[topic]
            chosen = self._choose(t, now_ns)
            switch = self._note(topic, t, chosen, now_ns)
        if switch is not None and self._on_switch is not None:
            self._on_switch(*switch)
        return chosen

    def report(self, now_ns: int) -> dict[str, Any]:
        """Per topic: the source in charge and each source's taken / yielded counts."""
        out: dict[str, Any] = {}
        for topic in self.topics:
            chosen = self.in_charge(topic, now_ns)
            with self._lock:
                t = self._topics[topic]
                out[topic] = {
                    'in_charge': chosen.name if chosen is not None else '',
                    'taken': dict(t.taken),
                    'yielded': dict(t.yielded),
                }
        return out

    def _choose(self, t: _Topic, now_ns: int) -> CommandSource | None:
        for source in self.sources:  # highest priority first
            last = t.last_ns.get(source.name)
            if last is not None and now_ns - last <= source.timeout * _NS_PER_S:
                return source
        return None

    def _note(
        self, topic: str, t: _Topic, chosen: CommandSource | None, now_ns: int
    ) -> tuple[str, str, str, str] | None:
        old = t.in_charge
        if chosen is old:
            return None
        t.in_charge = chosen
        self.switches += 1
        if old is None:
            why = 'the only live source' if chosen is not None else ''
        elif chosen is None or chosen.priority < old.priority:
            silent = (now_ns - t.last_ns[old.name]) / _NS_PER_S
            why = f'{old.name} silent for {silent:.3f} s'
        else:
            why = f'priority {chosen.priority} over {old.priority}'
        return (topic, old.name if old else '', chosen.name if chosen else '', why)
