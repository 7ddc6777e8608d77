"""The loop's order, derived from what each component reads and writes.

Each component of the loop declares the data it reads and writes, by name
(:mod:`rm_base.loop.data`); the order follows from those declarations, as in RMCS's
executor, so a new component joins by declaring its data and no code lists the order:

- a *writer* of a datum (writes it, does not read it) runs before everything that reads it;
- a *modifier* (reads and writes it, as a power limit scales the efforts) runs after its
  writers and before its plain readers; modifiers of one datum run in the order added;
- otherwise the order added decides, the components named late after the others (the
  loop's own: a stage that declares nothing runs before the actuators, as an input).

Two errors end a composition, each naming the components: a cycle (two components that
each need the other first) and an output that nothing reads (a component whose work would
be lost). A datum read but not written in the loop comes from outside it (ROS, a thread).
Pure: no threads, no clock.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Collection, Sequence
from typing import Protocol

from rm_base.loop.errors import LoopConfigError


class Declared(Protocol):
    """What the order needs of a component (read-only: a class attribute will do)."""

    @property
    def name(self) -> str:
        """Its name in messages."""

    @property
    def reads(self) -> tuple[str, ...]:
        """The data it reads."""

    @property
    def writes(self) -> tuple[str, ...]:
        """The data it writes; what it also reads, it modifies."""


def derive_order(components: Sequence[Declared], late: Collection[str] = ()) -> list[int]:
    """The indices of components in run order (see the module docstring).

    Raises:
        LoopConfigError: two components each need the other first (named with the data).
    """
    after: list[set[int]] = [set() for _ in components]  # after[j]: what must run before j
    why: dict[tuple[int, int], str] = {}
    writers: dict[str, list[int]] = {}
    modifiers: dict[str, list[int]] = {}
    readers: dict[str, list[int]] = {}
    for i, c in enumerate(components):
        reads, writes = set(c.reads), set(c.writes)
        for datum in writes - reads:
            writers.setdefault(datum, []).append(i)
        for datum in writes & reads:
            modifiers.setdefault(datum, []).append(i)
        for datum in reads - writes:
            readers.setdefault(datum, []).append(i)

    def edge(first: int, then: int, datum: str) -> None:
        if first != then:
            after[then].add(first)
            why.setdefault((first, then), datum)

    for datum in set(writers) | set(modifiers):
        chain = modifiers.get(datum, [])
        for w in writers.get(datum, ()):
            for j in chain + readers.get(datum, []):
                edge(w, j, datum)
        for a, b in itertools.pairwise(chain):
            edge(a, b, datum)
        for m in chain:
            for r in readers.get(datum, ()):
                edge(m, r, datum)
    order: list[int] = []
    waiting = [len(a) for a in after]
    then: list[list[int]] = [[] for _ in components]
    for j, firsts in enumerate(after):
        for i in firsts:
            then[i].append(j)
    rank = [(c.name in late, i) for i, c in enumerate(components)]
    ready = [rank[j] for j, n in enumerate(waiting) if n == 0]
    heapq.heapify(ready)
    while ready:
        _, i = heapq.heappop(ready)
        order.append(i)
        for j in then[i]:
            waiting[j] -= 1
            if waiting[j] == 0:
                heapq.heappush(ready, rank[j])
    if len(order) < len(components):
        cycle = _cycle(after, set(range(len(components))) - set(order))
        steps = ', '.join(
            f'{components[j].name!r} needs {why[(i, j)]!r} from {components[i].name!r}'
            for j, i in zip(cycle, cycle[1:] + cycle[:1], strict=False)
        )
        raise LoopConfigError(f"the loop's components form a cycle: {steps}")
    return order


def unread_outputs(components: Sequence[Declared]) -> list[tuple[str, str]]:
    """``(component, datum)`` for each datum written that no component only reads.

    A modifier's output needs a plain reader after it too; the last writer is named.
    """
    plain_read = {d for c in components for d in c.reads if d not in c.writes}
    last_writer: dict[str, str] = {}
    for c in components:
        for datum in c.writes:
            last_writer[datum] = c.name
    return [(name, datum) for datum, name in last_writer.items() if datum not in plain_read]


def _cycle(after: list[set[int]], left: set[int]) -> list[int]:
    """A cycle among the components left unordered, as a list (each needs the next first)."""
    start = min(left)
    path: list[int] = [start]
    seen = {start: 0}
    while True:
        nxt = min(i for i in after[path[-1]] if i in left)
        if nxt in seen:
            return path[seen[nxt]:]
        seen[nxt] = len(path)
        path.append(nxt)
