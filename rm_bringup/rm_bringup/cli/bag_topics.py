"""Which of a bag's topics ``rmcli bag play`` plays, and under which names.

``--topics`` picks topics; without it, a topic some other node publishes now is left out
(replaying a recorded /chassis_state beside a live robot's would mix the two), and said.
``--remap FROM:=TO`` publishes a recorded topic under another name. A topic with two types
in one bag, or two recorded topics that would land on one name with different types, are
refused.
"""

from __future__ import annotations

import sys
from pathlib import Path

from .errors import CliError

DISCOVERY_S = 0.5  # shortest wait for the graph before judging what is published live [s]


def absolute(topic: str) -> str:
    """Topic with a leading slash."""
    return topic if topic.startswith('/') else f'/{topic}'


def parse_remaps(items: list[str]) -> dict[str, str]:
    """``['/a:=/b', ...]`` as {recorded topic: published topic}, both absolute.

    Raises:
        CliError: an item without ``:=``, an empty side, or one topic remapped twice.
    """
    remaps: dict[str, str] = {}
    for item in items:
        source, sep, target = item.partition(':=')
        if not sep or not source.strip() or not target.strip():
            raise CliError(f'--remap {item!r}: write FROM:=TO, e.g. /cmd_vel:=/vel_cmd')
        source, target = absolute(source.strip()), absolute(target.strip())
        if source in remaps:
            raise CliError(f'--remap: {source} is remapped twice')
        remaps[source] = target
    return remaps


def check_remaps(remaps: dict[str, str], by_topic: dict[str, list]) -> None:
    """Warn of remaps of topics not played; refuse two types landing on one name.

    Raises:
        CliError: two recorded topics of different types would be published on one name.
    """
    missing = sorted(set(remaps) - set(by_topic))
    if missing:
        print(f'rmcli: warning: --remap of topics not played: {", ".join(missing)}',
              file=sys.stderr)
    published: dict[str, tuple[str, str]] = {}  # published topic -> (recorded topic, type)
    for topic, conns in by_topic.items():
        name = remaps.get(topic, topic)
        other = published.get(name)
        if other is not None and other[1] != conns[0].msgtype:
            raise CliError(
                f'{topic} ({conns[0].msgtype}) and {other[0]} ({other[1]}) would both be '
                f'published on {name}'
            )
        published[name] = (topic, conns[0].msgtype)


def select(connections, topics: list[str], path: Path) -> list:
    """The connections of the topics asked for (all without ``--topics``).

    Raises:
        CliError: the bag has no topics, or none of those asked for.
    """
    if not topics:
        if not connections:
            raise CliError(f'nothing to play in {path}: the bag has no topics')
        return list(connections)
    wanted = {absolute(t) for t in topics}
    selected = [c for c in connections if c.topic in wanted]
    missing = wanted - {c.topic for c in selected}
    if missing and selected:
        print(f'rmcli: warning: not in the bag: {", ".join(sorted(missing))}', file=sys.stderr)
    if not selected:
        raise CliError(
            f'none of {", ".join(sorted(wanted))} is in {path}; it has '
            f'{", ".join(sorted({c.topic for c in connections})) or "no topics"}'
        )
    return selected


def not_live(node, connections, remaps: dict[str, str], path: Path) -> list:
    """The connections whose topic no node of the graph publishes now.

    A recorded /chassis_state played into a running robot would mix with the live one (the
    status line, a recorder, a planner would all see both): without ``--topics``, what is
    published live is left out, and said. Hidden nodes (``_`` first: rmcli's and ros2cli's
    own, such as a `topic pub` that just ended and discovery still lists) do not count.
    """
    from .topic_list import settled

    def published(topic: str) -> bool:
        return any(not info.node_name.startswith('_')
                   for info in node.get_publishers_info_by_topic(topic))

    played = {remaps.get(c.topic, c.topic) for c in connections}

    def graph() -> list:
        # endpoints are discovered one by one: a publisher found for a topic already listed
        # (by a subscriber of it) is news too, and restarts the wait for the graph to settle
        return node.get_topic_names_and_types() + [
            (f'{topic} (published)', []) for topic in sorted(played) if published(topic)]

    settled(graph, DISCOVERY_S)
    live = sorted({c.topic for c in connections if published(remaps.get(c.topic, c.topic))})
    if live:
        print(f'rmcli: not playing {", ".join(live)}: published live by another node (name '
              'them in --topics to play them too)', file=sys.stderr)
    kept = [c for c in connections if c.topic not in live]
    if not kept:
        raise CliError(f'nothing to play from {path}: every topic of it is published live; '
                       'name the ones to play in --topics')
    return kept


def by_topic(connections) -> dict[str, list]:
    """Connections grouped by topic.

    Raises:
        CliError: a topic with more than one type in the bag.
    """
    grouped: dict[str, list] = {}
    for connection in connections:
        grouped.setdefault(connection.topic, []).append(connection)
    for topic, conns in grouped.items():
        if len({c.msgtype for c in conns}) > 1:
            raise CliError(f'topic {topic} has more than one type in the bag')
    return grouped
