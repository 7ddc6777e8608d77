"""The interpreter's garbage collection, done by the control loop after its send.

CPython collects reference cycles when allocations pass a threshold, in whichever thread
allocates at that moment, holding the interpreter lock throughout: the loop, or an edge
thread the loop then waits for. Measured in the robot's process (docs/PERFORMANCE.md,
"The loop collects the garbage"), a young collection takes 0.07 ms typically and about
1 ms at worst, a full one over 20 ms: a tick that meets one sends late, and the wire shows the gap.

So while a loop's thread runs, automatic collection is off (``gc.disable``) and the loop
collects after its tick's frames went out, in the idle time before the next deadline: the
generation CPython's own thresholds would pick (``gc.get_threshold``), at most one
collection per tick. The objects that exist when the first loop starts (modules, nodes,
the configuration) are collected once and frozen (``gc.freeze``), so a full collection
scans only what was made since; they are unfrozen when the last loop stops.

CPython also skips a due full collection while fewer objects reached the oldest
generation since its last collection than a quarter of those it kept then (a full
collection costs the whole heap; this bounds its share). It does not expose those two
counts, so the collecting loop keeps them (:class:`OldestGeneration`): the objects it
finds there after a full collection, and the survivors of each generation-1 collection,
which move there.

``gc`` is the process's: with several loops in one process (the CAN loop and rm_manual's
100 Hz loop), the fastest collects for all, the others only keep automatic collection
off, and the last one to stop turns it back on.
"""

from __future__ import annotations

import gc
import itertools
import threading
from dataclasses import dataclass, field

_lock = threading.Lock()
_order = itertools.count()
_holders: list[Holder] = []
#: Whether automatic collection was on when the first loop took it over.
_was_enabled = [True]


@dataclass(eq=False)
class Holder:
    """One loop's share of the process's garbage collection (see :func:`take_over`)."""

    rate_hz: float
    order: int = field(default_factory=lambda: next(_order))

    @property
    def collects(self) -> bool:
        """Whether this loop is the one that collects (the fastest; the first of equals)."""
        with _lock:
            return bool(_holders) and _collector() is self


def _collector() -> Holder:
    return min(_holders, key=lambda h: (-h.rate_hz, h.order))


def take_over(rate_hz: float) -> Holder:
    """Turn automatic collection off for a loop of rate_hz; give it back with :func:`give_back`."""
    holder = Holder(rate_hz)
    with _lock:
        if not _holders:
            _was_enabled[0] = gc.isenabled()
            gc.disable()
            gc.collect()  # frozen garbage would never be freed
            gc.freeze()
            oldest.total = oldest.pending = 0
        _holders.append(holder)
    return holder


def give_back(holder: Holder) -> None:
    """End a loop's :func:`take_over`; the last one restores automatic collection."""
    with _lock:
        if holder not in _holders:
            return
        _holders.remove(holder)
        if not _holders:
            gc.unfreeze()
            if _was_enabled[0]:
                gc.enable()


@dataclass
class OldestGeneration:
    """What CPython weighs before a full collection, kept by the collecting loop.

    Attributes:
        total: objects in the oldest generation after its last collection.
        pending: objects that reached it since (survivors of generation-1 collections).
    """

    total: int = 0
    pending: int = 0

    @property
    def worth_collecting(self) -> bool:
        """Whether a due full collection runs: a quarter of ``total`` has arrived since."""
        return self.pending >= self.total // 4


#: The process's (the frozen objects are in no generation: a loop starts from zero).
oldest = OldestGeneration()


def due_generation(
    counts: tuple[int, int, int],
    thresholds: tuple[int, int, int],
    record: OldestGeneration | None = None,
) -> int | None:
    """The generation CPython would collect at these counts, or None (CPython 3.11 rule).

    ``counts[0]`` is allocations minus deallocations since the last collection;
    ``counts[1]`` and ``counts[2]`` the collections of the generation below since the last
    collection of their own. Nothing is due until generation 0 is over its threshold; then
    the oldest generation over its threshold is collected, but the oldest one only when
    ``record`` (the oldest generation's, usually :data:`oldest`) says it is worth it
    (None: always).
    """
    if thresholds[0] == 0 or counts[0] <= thresholds[0]:  # threshold 0: collection off
        return None
    if counts[2] > thresholds[2] and (record is None or record.worth_collecting):
        return 2
    if counts[1] > thresholds[1]:
        return 1
    return 0


def collect_if_due(holder: Holder) -> int | None:
    """If holder is the collecting loop, collect the generation that is due.

    Returns:
        The generation collected; None if none was (nothing due, or another loop collects).
    """
    if not holder.collects:
        return None
    generation = due_generation(gc.get_count(), gc.get_threshold(), oldest)
    if generation == 2:
        gc.collect(2)
        oldest.total, oldest.pending = len(gc.get_objects(2)), 0
    elif generation == 1:
        young = len(gc.get_objects(0)) + len(gc.get_objects(1))
        oldest.pending += max(0, young - gc.collect(1))  # collect returns the unreachable
    elif generation == 0:
        gc.collect(0)
    return generation
