import itertools
import math

import pytest
from rm_base.control import TdParams, TrackingDifferentiator, fhan
from rm_base.errors import ConfigError, InputRejectedError


def test_when_far_below_target_expect_full_positive_acceleration():
    # x1 = -1 (1 below the target), x2 = 0, r = 100, h = 0.001:
    # d = r h = 0.1, d0 = h d = 1e-4, y = x1 + h x2 = -1; |y| > d0, so
    # a = x2 + (sqrt(d^2 + 8 r |y|) - d) / 2 * sign(y) = -(sqrt(800.01) - 0.1) / 2 = -14.09
    # |a| > d: fhan = -r sign(a) = +100
    assert fhan(-1.0, 0.0, 100.0, 0.001) == 100.0


def test_when_far_above_target_expect_full_negative_acceleration():
    # Mirror of the case above: fhan is odd in (x1, x2)
    assert fhan(1.0, 0.0, 100.0, 0.001) == -100.0


def test_when_close_to_target_expect_linear_acceleration():
    # x1 = -1e-5, x2 = 0, r = 100, h = 0.001: d = 0.1, d0 = 1e-4, y = -1e-5, |y| <= d0:
    # a = x2 + y / h = -0.01; |a| <= d: fhan = -r a / d = -100 * -0.01 / 0.1 = 10
    assert fhan(-1e-5, 0.0, 100.0, 0.001) == pytest.approx(10.0)


def test_when_moving_fast_towards_target_expect_braking():
    # x1 = -0.01, x2 = +10 (will overshoot: braking distance x2^2 / 2r = 0.5 > 0.01),
    # r = 100, h = 0.001: d = 0.1, y = -0.01 + 0.01 = 0 <= d0: a = x2 + 0 = 10 > d:
    # fhan = -r sign(a) = -100
    assert fhan(-0.01, 10.0, 100.0, 0.001) == -100.0


def test_when_at_rest_on_target_expect_zero_acceleration():
    assert fhan(0.0, 0.0, 100.0, 0.001) == 0.0


def test_when_first_update_expect_output_starts_at_target():
    td = TrackingDifferentiator(TdParams(100.0))
    assert td.update(3.0, 0.001) == 3.0
    assert td.derivative == 0.0


def test_when_reset_to_value_expect_tracking_starts_there():
    td = TrackingDifferentiator(TdParams(100.0))
    td.reset(0.0)
    # x1 = 0 + h * x2 = 0 (x2 = 0); then x2 = 0 + h * fhan = 0.001 * 100 = 0.1
    assert td.update(1.0, 0.001) == 0.0
    assert td.derivative == pytest.approx(0.1)


def test_when_step_expect_settles_in_minimum_time_without_overshoot():
    # Time-optimal with |acceleration| <= r: a step of A = 1 with r = 100 takes
    # 2 * sqrt(A / r) = 0.2 s (accelerate 0.1 s, brake 0.1 s), peak speed r * 0.1 = 10.
    dt = 0.001
    td = TrackingDifferentiator(TdParams(100.0))
    td.reset(0.0)
    values, rates = [], [0.0]
    for _ in range(300):
        values.append(td.update(1.0, dt))
        rates.append(td.derivative)
    settled = values[249:]  # from t = 0.25 s, a few steps after 0.2 s
    assert all(abs(value - 1.0) < 1e-3 for value in settled)
    assert max(values) <= 1.0 + 1e-3
    assert max(rates) <= 10.0 * 1.01
    accelerations = [(b - a) / dt for a, b in itertools.pairwise(rates)]
    assert max(abs(acc) for acc in accelerations) <= 100.0 + 1e-9


def test_when_input_is_a_ramp_expect_derivative_tracks_its_slope():
    # v(t) = 2 t: once tracking, x2 -> dv/dt = 2
    dt = 0.001
    td = TrackingDifferentiator(TdParams(100.0))
    td.reset(0.0)
    for step in range(1, 1001):
        td.update(2.0 * step * dt, dt)
    assert td.derivative == pytest.approx(2.0, abs=1e-6)


def test_when_input_is_a_ramp_expect_lag_of_braking_distance():
    # fhan sees the target as if it would stop, so x1 settles where fhan = 0 with x2 = 2:
    # a = x2 - (sqrt(d^2 + 8 r |y|) - d) / 2 = 0, with d = r h = 0.1:
    # |y| = ((2 x2 + d)^2 - d^2) / (8 r) = (4.1^2 - 0.1^2) / 800 = 0.021, and
    # y = x1_before + h x2 - v = x1_after - v, so x1 lags v by 0.021 (about x2^2 / 2r).
    dt = 0.001
    td = TrackingDifferentiator(TdParams(100.0))
    td.reset(0.0)
    for step in range(1, 1001):
        td.update(2.0 * step * dt, dt)
    assert td.value == pytest.approx(2.0 - 0.021, abs=1e-6)


def test_when_filter_factor_larger_expect_slower_approach():
    dt = 0.001
    fast = TrackingDifferentiator(TdParams(100.0))
    slow = TrackingDifferentiator(TdParams(100.0, filter_factor_s=0.02))
    fast.reset(0.0)
    slow.reset(0.0)
    for _ in range(150):
        fast.update(1.0, dt)
        slow.update(1.0, dt)
    # A larger h0 brakes earlier (it plans h0 ahead), so mid-manoeuvre it is behind.
    assert slow.value < fast.value


@pytest.mark.parametrize(('target', 'dt'), [(math.nan, 0.001), (1.0, 0.0), (1.0, math.inf)])
def test_when_input_invalid_expect_rejected(target, dt):
    td = TrackingDifferentiator(TdParams(100.0))
    with pytest.raises(InputRejectedError):
        td.update(target, dt)


@pytest.mark.parametrize(
    ('kwargs', 'field'),
    [
        ({'acceleration_limit': 0.0}, 'acceleration_limit'),
        ({'acceleration_limit': math.inf}, 'acceleration_limit'),
        ({'acceleration_limit': 1.0, 'filter_factor_s': -0.001}, 'filter_factor_s'),
    ],
)
def test_when_params_invalid_expect_config_error(kwargs, field):
    with pytest.raises(ConfigError, match=field):
        TdParams(**kwargs)
