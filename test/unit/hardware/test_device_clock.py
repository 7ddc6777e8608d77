"""DeviceClock: host stamps from a device's millisecond counter."""

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.hardware.device_clock import DeviceClock

MS = 1_000_000
T0 = 7_000_000_000_000  # host clock at the first sample [ns]


def test_when_a_backlog_is_read_at_once_expect_each_frame_at_its_own_time():
    clock = DeviceClock()
    # 400 Hz frames (2.5 ms apart, counter in whole ms): the first 10 read as they come...
    for k in range(10):
        assert clock.stamp_ns(100 + 5 * k // 2, T0 + 5 * k * MS // 2) == T0 + 5 * k // 2 * MS
    # ...then the reader stalls 100 ms and reads 40 queued frames in the same instant
    read_at = T0 + 125 * MS
    stamps = [clock.stamp_ns(100 + 5 * k // 2, read_at) for k in range(10, 50)]
    assert stamps == [T0 + 5 * k // 2 * MS for k in range(10, 50)]


@pytest.mark.parametrize(
    ('device_ms', 'receive_ms', 'stamp_ms'),
    [
        # the counter wraps at 2**32 ms: time goes on
        ((2**32 - 2, 2**32 - 1, 0, 1), (0, 1, 2, 3), (0, 1, 2, 3)),
        # a restarted device (counter back to 0): the estimate starts over at the restart
        ((50_000, 50_010, 0, 10), (0, 10, 20, 30), (0, 10, 20, 30)),
        # the counter jumps 5 s ahead: starts over too
        ((10, 20, 5_030, 5_040), (0, 10, 20, 30), (0, 10, 20, 30)),
        # a frame read before its device time (a clock running fast): never after receipt
        ((0, 10, 20), (5, 12, 21), (5, 12, 21)),
        # a counter that does not move (left at zero): stamped at receipt
        ((0, 0, 0), (0, 40, 90), (0, 40, 90)),
    ],
)
def test_table(device_ms, receive_ms, stamp_ms):
    clock = DeviceClock()
    stamps = [clock.stamp_ns(d, T0 + r * MS) for d, r in zip(device_ms, receive_ms, strict=True)]
    assert stamps == [T0 + s * MS for s in stamp_ms]


def test_when_the_window_passes_expect_the_estimate_to_follow_a_slower_link():
    clock = DeviceClock(window_s=1.0)
    assert clock.stamp_ns(0, T0) == T0
    # from now on every frame takes 3 ms more (e.g. a busier USB adapter): after the
    # window the fastest frame in it is a 3 ms one
    stamps = [clock.stamp_ns(10 * k, T0 + (10 * k + 3) * MS) for k in range(1, 150)]
    assert stamps[0] == T0 + 10 * MS  # still measured against the 0 ms frame
    assert stamps[-1] == T0 + (10 * 149 + 3) * MS


@given(
    delays=st.lists(st.integers(min_value=0, max_value=200), min_size=2, max_size=300),
    fastest=st.integers(min_value=0, max_value=299),
)
def test_when_one_frame_came_through_without_delay_expect_exact_stamps_after_it(delays, fastest):
    # frames every 5 ms with random queueing delays [ms], one of them without delay
    fastest %= len(delays)
    delays[fastest] = 0
    clock = DeviceClock(window_s=10.0)
    for k, delay in enumerate(delays):
        stamp = clock.stamp_ns(5 * k, T0 + (5 * k + delay) * MS)
        assert stamp <= T0 + (5 * k + delay) * MS  # never after receipt
        assert stamp >= T0 + 5 * k * MS  # never before the sample was taken
        if k >= fastest:
            assert stamp == T0 + 5 * k * MS


def test_invalid_arguments():
    with pytest.raises(ValueError, match='must be > 0'):
        DeviceClock(window_s=0.0)
