"""Garbage collection run by the loop: which generation is due, who collects, give-back."""

import gc

import pytest
from rm_base.hardware import garbage

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
