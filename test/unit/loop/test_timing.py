"""DurationHistogram: p50 / p99 / max of the loop's components, window and total."""

import pytest
from rm_base.loop.timing import BUCKET_EDGES_NS, DurationHistogram


def test_when_nothing_is_recorded_expect_an_empty_summary():
    summary = DurationHistogram().total()
    assert (summary.count, summary.p50_us, summary.p99_us, summary.max_us) == (0, 0.0, 0.0, 0.0)


def test_percentiles_are_within_five_percent_above_the_true_value():
    h = DurationHistogram()
    # 1..1000 µs, one each: the true p50 is 500 µs, the true p99 990 µs, the max 1000 µs.
    for us in range(1, 1001):
        h.record(us * 1000)
    summary = h.total()
    assert summary.count == 1000
    assert 500 <= summary.p50_us <= 500 * 1.05
    assert 990 <= summary.p99_us <= 1000  # capped at the exact maximum
    assert summary.max_us == 1000


def test_one_outlier_in_a_hundred_sets_the_p99_and_the_max():
    h = DurationHistogram()
    for _ in range(98):
        h.record(10_000)  # 10 µs
    h.record(2_000_000)  # 2 ms: rank 99 of 99 ... p99 is the 99th smallest of 100
    h.record(3_000_000)
    summary = h.total()
    assert summary.p50_us == pytest.approx(10, rel=0.05)
    assert summary.p99_us == pytest.approx(2000, rel=0.05)
    assert summary.max_us == 3000


def test_take_window_starts_a_new_window_and_keeps_the_total():
    h = DurationHistogram()
    h.record(5_000_000)
    assert h.take_window().max_us == 5000
    h.record(1_000)
    assert h.window().count == 1
    assert h.window().max_us == 1
    assert h.total().count == 2
    assert h.total().max_us == 5000


def test_durations_beyond_the_last_edge_count_at_their_maximum():
    h = DurationHistogram()
    beyond = BUCKET_EDGES_NS[-1] + 1
    h.record(beyond)
    assert h.total().p99_us == beyond / 1e3
