"""The interpreter's garbage collection, done by the control loop after its send.

CPython collects reference cycles when allocations pass a threshold, in whichever thread
allocates at that moment, holding the interpreter lock throughout: the loop, or an edge
thread the loop then waits for. Measured in the robot's process (docs/PERFORMANCE.md,
"Garbage collection"), a young collection takes 0.07 ms typically and about 1 ms at worst,
a full one over 20 ms: a tick that meets one sends late, and the wire shows the gap.

So while a loop's thread runs, automatic collection is off (``gc.disable``) and the loop
collects after its tick's frames went out, in the idle time before the next deadline: the
generation CPython's own thresholds would pick (``gc.get_threshold``), at most one
collection per tick. The objects that exist when the first loop starts (modules, nodes,
the configuration) are collected once and frozen (``gc.freeze``), so a full collection
scans only what was made since; they are unfrozen when the last loop stops.

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


def due_generation(
    counts: tuple[int, int, int], thresholds: tuple[int, int, int]
) -> int | None:
    """The generation CPython would collect at these counts, or None (CPython 3.11 rule).

    ``counts[0]`` is allocations minus deallocations since the last collection;
    ``counts[1]`` and ``counts[2]`` the collections of the generation below since the last
    collection of their own. Nothing is due until generation 0 is over its threshold; then
    the oldest generation over its threshold is collected.
    """
    if thresholds[0] == 0 or counts[0] <= thresholds[0]:  # threshold 0: collection off
        return None
    for generation in (2, 1):
        if counts[generation] > thresholds[generation]:
            return generation
    return 0


def collect_if_due(holder: Holder) -> int | None:
    """If holder is the collecting loop, collect the generation that is due.

    Returns:
        The generation collected; None if none was (nothing due, or another loop collects).
    """
    if not holder.collects:
        return None
    generation = due_generation(gc.get_count(), gc.get_threshold())
    if generation is not None:
        gc.collect(generation)
    return generation
