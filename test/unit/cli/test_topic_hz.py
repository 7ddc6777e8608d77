"""topic hz statistics (RateWindow) and its output format."""

import pytest
from rm_bringup.cli.topic_hz import RateStats, RateWindow

MS = 1_000_000  # ns


def test_no_statistics_before_the_second_message():
    window = RateWindow()
    assert window.stats() is None
    window.add(5 * MS)
    assert window.stats() is None


def test_rate_min_max_and_std_dev_of_the_intervals():
    window = RateWindow()
    for t in (0, 100, 300, 400):  # [ms] -> intervals 100, 200, 100 ms
        window.add(t * MS)
    stats = window.stats()
    # mean 133.33 ms -> 7.5 Hz; std dev sqrt(((-33.3)^2*2 + 66.7^2)/3) = 47.14 ms
    assert stats.rate_hz == pytest.approx(7.5)
    assert stats.min_s == pytest.approx(0.1)
    assert stats.max_s == pytest.approx(0.2)
    assert stats.std_dev_s == pytest.approx(0.0471405, rel=1e-5)
    assert stats.window == 3


def test_only_the_last_window_intervals_count():
    window = RateWindow(window_size=2)
    for t in (0, 500, 600, 700):  # intervals 500, 100, 100 ms; the window keeps 100, 100
        window.add(t * MS)
    assert window.stats().rate_hz == pytest.approx(10.0)
    assert window.stats().window == 2


def test_time_going_backwards_restarts_the_statistics():
    window = RateWindow()
    for t in (1000, 1100, 50):
        window.add(t * MS)
    assert window.stats() is None
    window.add(70 * MS)
    assert window.stats().max_s == pytest.approx(0.02)


def test_output_is_ros2s_two_lines():
    stats = RateStats(rate_hz=20.0, min_s=0.049, max_s=0.0512, std_dev_s=0.000321, window=40)
    assert stats.format() == (
        'average rate: 20.000\n\tmin: 0.049s max: 0.051s std dev: 0.00032s window: 40'
    )
