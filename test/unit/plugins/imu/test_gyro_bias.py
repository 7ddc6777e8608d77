"""Gyro bias at rest: the window keeps the last duration, the bias needs a still sensor."""

import pytest
from rm_plugins.imu.gyro_bias import GyroWindow, NotAtRestError, RestLimits, bias_at_rest

MS = 1_000_000
LIMITS = RestLimits(duration_s=1.0, max_rate=0.05, max_spread=0.02)


def window(rates, period_ms=10):
    w = GyroWindow(LIMITS.duration_s)
    for i, rate in enumerate(rates):
        w.add(i * period_ms * MS, rate)
    return w


def test_the_window_keeps_only_the_last_duration():
    w = window([(float(i), 0.0, 0.0) for i in range(300)])  # 3 s at 100 Hz
    kept = w.snapshot()
    assert len(kept) == 101 and kept[0][1][0] == 199.0 and kept[-1][1][0] == 299.0
    w.clear()
    assert w.snapshot() == []


def test_the_bias_is_the_mean_of_a_still_window():
    rates = [(0.01 + 0.001 * (i % 2), -0.02, 0.0) for i in range(101)]
    assert bias_at_rest(window(rates).snapshot(), LIMITS) == pytest.approx(
        (0.0105, -0.02, 0.0), abs=1e-4
    )


@pytest.mark.parametrize(
    ('rates', 'period_ms', 'message'),
    [
        ([(0.0, 0.0, 0.0)] * 10, 10, 'not enough IMU data: 10 samples over 0.09 s'),
        ([(0.0, 0.0, 0.0)] * 50, 10, r'not enough IMU data: 50 samples over 0.49 s, need 20 '),
        ([(0.0, 0.1, 0.0), (0.0, -0.1, 0.0)] * 50, 10, 'moving: the rate varies by 0.1000'),
        ([(0.06, 0.0, 0.0)] * 101, 10, 'turning: mean rate 0.0600 rad/s'),
    ],
    ids=['few', 'short', 'shaking', 'turning'],
)
def test_a_window_that_is_not_at_rest_is_refused_with_the_numbers(rates, period_ms, message):
    with pytest.raises(NotAtRestError, match=message):
        bias_at_rest(window(rates, period_ms).snapshot(), LIMITS)
