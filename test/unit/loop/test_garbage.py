"""Garbage collection run by the loop: which generation is due, who collects, give-back."""

import gc

import pytest
from rm_base.loop import garbage

THRESHOLDS = (700, 10, 10)  # CPython's defaults


@pytest.mark.parametrize(('counts', 'due'), [
    ((0, 0, 0), None),
    ((700, 9, 9), None),  # at the threshold, not over it
    ((701, 0, 0), 0),
    ((701, 10, 0), 0),
    ((701, 11, 0), 1),
    ((701, 11, 11), 2),  # the oldest over its threshold
    ((701, 0, 11), 2),
    ((5, 11, 11), None),  # nothing before generation 0 is over
])
def test_the_generation_due_is_the_one_cpython_would_collect(counts, due):
    assert garbage.due_generation(counts, THRESHOLDS) == due


@pytest.mark.parametrize(('pending', 'total', 'due'), [
    (0, 0, 2),  # nothing there yet: as cheap as it gets
    (24, 100, 0),  # under a quarter arrived: skipped, and generation 1 is not over either
    (25, 100, 2),
    (1000, 100, 2),
])
def test_a_full_collection_waits_for_a_quarter_of_the_oldest_generation(pending, total, due):
    oldest = garbage.OldestGeneration(total=total, pending=pending)
    assert garbage.due_generation((701, 0, 11), THRESHOLDS, oldest) == due


def test_a_skipped_full_collection_leaves_generation_1_due():
    oldest = garbage.OldestGeneration(total=100, pending=0)
    assert garbage.due_generation((701, 11, 11), THRESHOLDS, oldest) == 1


def test_a_zero_threshold_means_never():
    assert garbage.due_generation((10_000, 100, 100), (0, 10, 10)) is None


@pytest.fixture
def restored():
    yield
    gc.enable()
    gc.unfreeze()


def test_the_fastest_loop_collects_and_the_last_to_stop_turns_collection_back_on(restored):
    assert gc.isenabled()
    manual = garbage.take_over(100.0)
    assert not gc.isenabled() and manual.collects
    can_loop = garbage.take_over(1000.0)
    other = garbage.take_over(1000.0)
    assert can_loop.collects and not manual.collects and not other.collects
    garbage.give_back(can_loop)
    assert other.collects  # the next fastest takes over the collecting
    garbage.give_back(other)
    assert manual.collects and not gc.isenabled()
    assert gc.get_freeze_count() > 0  # what existed at the start is not scanned
    garbage.give_back(manual)
    garbage.give_back(manual)  # twice: no effect
    assert gc.isenabled() and not manual.collects and gc.get_freeze_count() == 0


def test_the_collecting_loop_collects_what_is_due_and_frees_cycles(restored):
    holder = garbage.take_over(1000.0)
    try:
        gc.collect()
        for _ in range(2000):  # reference cycles: only a collection frees them
            a = []
            a.append(a)
        assert gc.get_count()[0] > gc.get_threshold()[0]  # automatic collection is off
        assert garbage.collect_if_due(holder) == 0
        assert gc.get_count()[0] < gc.get_threshold()[0]
        assert garbage.collect_if_due(holder) is None  # nothing due now
    finally:
        garbage.give_back(holder)


def test_a_loop_that_does_not_collect_leaves_the_count_alone(restored):
    fast, slow = garbage.take_over(1000.0), garbage.take_over(100.0)
    try:
        for _ in range(2000):
            a = []
            a.append(a)
        assert garbage.collect_if_due(slow) is None
        assert gc.get_count()[0] > gc.get_threshold()[0]
    finally:
        garbage.give_back(slow)
        garbage.give_back(fast)


def _collect_while_allocating(holder, rounds, keep=None):
    """Allocate cycles (and keep some objects when keep is a list); collect what is due."""
    done = []
    for _ in range(rounds):
        for _ in range(gc.get_threshold()[0] + 1):
            a = []
            a.append(a)
            if keep is not None:
                keep.append([])
        done.append(garbage.collect_if_due(holder))
    return done


def test_the_loop_skips_full_collections_of_a_heap_that_is_not_growing(restored):
    thresholds = gc.get_threshold()
    gc.set_threshold(100, 2, 2)
    holder = garbage.take_over(1000.0)
    try:
        keep = [[] for _ in range(20_000)]  # long-lived: in the oldest generation soon
        done = _collect_while_allocating(holder, 30)
        assert 2 in done
        assert garbage.oldest.total >= len(keep)  # counted after the full collection
        # only garbage since: 10 full collections would be due, none is worth it
        done = _collect_while_allocating(holder, 100)
        assert 2 not in done and 1 in done and 0 in done
        assert garbage.oldest.pending < garbage.oldest.total // 4
        # a growing heap: a quarter more reaches the oldest generation, which is collected
        grown: list[list[object]] = []
        done = _collect_while_allocating(holder, 200, keep=grown)
        assert 2 in done and len(grown) >= len(keep) // 4
    finally:
        garbage.give_back(holder)
        gc.set_threshold(*thresholds)
