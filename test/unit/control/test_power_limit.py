import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.control import (
    ChassisPowerModel,
    estimate_power,
    fit_power_model,
    limit_power,
    power_limit_scale,
)
from rm_base.errors import ConfigError, InputRejectedError

# k1 = 2.5 W/(N·m)², k2 = 0.05 W/(rad/s)², 5 W static. With four wheels at 1 N·m and
# 5 rad/s: a = k1 * sum tau² = 2.5 * 4 = 10, b = sum tau * w = 4 * 5 = 20,
# c0 = k2 * sum w² + static = 0.05 * 100 + 5 = 10, so P(s) = 10 s² + 20 s + 10.
MODEL = ChassisPowerModel(k1=2.5, k2=0.05, static_power_w=5.0)
SPEEDS = (5.0, 5.0, 5.0, 5.0)
DRIVE = (1.0, 1.0, 1.0, 1.0)


def test_when_estimating_expect_sum_of_mechanical_copper_speed_and_static_power():
    model = ChassisPowerModel(k1=2.0, k2=0.01, static_power_w=5.0)
    # tau * w: 1*10 + (-1)(-10) + 2*20 + 0.5*5 = 10 + 10 + 40 + 2.5 = 62.5
    # k1 sum tau² = 2 * (1 + 1 + 4 + 0.25) = 12.5; k2 sum w² = 0.01 * (100+100+400+25) = 6.25
    # P = 62.5 + 12.5 + 6.25 + 5 = 86.25
    power = estimate_power(model, (1.0, -1.0, 2.0, 0.5), (10.0, -10.0, 20.0, 5.0))
    assert power == pytest.approx(86.25)


def test_when_request_within_limit_expect_scale_one():
    # P(1) = 10 + 20 + 10 = 40 <= 50
    assert power_limit_scale(MODEL, DRIVE, SPEEDS, 50.0) == 1.0


def test_when_request_over_limit_expect_larger_root_of_power_equals_limit():
    # 10 s² + 20 s + 10 = 22.5  ->  s² + 2 s - 1.25 = 0  ->  s = -1 + sqrt(2.25) = 0.5
    assert power_limit_scale(MODEL, DRIVE, SPEEDS, 22.5) == pytest.approx(0.5)


def test_when_limited_expect_one_common_factor_and_power_at_limit():
    result = limit_power(MODEL, (1.0, 2.0, -1.0, 0.0), SPEEDS, 22.5)
    # a = 2.5 * (1 + 4 + 1) = 15, b = 5 * (1 + 2 - 1) = 10, c0 = 10:
    # 15 s² + 10 s - 12.5 = 0  ->  s = (-10 + sqrt(100 + 750)) / 30 = (-10 + 29.1548) / 30
    #                                = 0.638493
    assert result.scale == pytest.approx(0.638493, rel=1e-5)
    assert result.torques == pytest.approx(tuple(result.scale * t for t in (1.0, 2.0, -1.0, 0.0)))
    # Before: 15 + 10 + 10 = 35 W; after: the limit.
    assert result.requested_power_w == pytest.approx(35.0)
    assert result.power_w == pytest.approx(22.5)


def test_when_regenerating_within_limit_expect_torque_not_scaled_up():
    braking = (-1.0, -1.0, -1.0, -1.0)
    # a = 10, b = -20, c0 = 10: P(1) = 0 <= 6; a larger braking torque would be "cheaper"
    # still (down to the vertex s = 1), but the factor never exceeds 1.
    assert power_limit_scale(MODEL, braking, SPEEDS, 6.0) == 1.0


def test_when_braking_copper_loss_exceeds_limit_expect_braking_reduced_to_limit():
    braking = (-4.0, -4.0, -4.0, -4.0)
    # a = 2.5 * 64 = 160, b = -4 * 4 * 5 = -80, c0 = 10: P(1) = 160 - 80 + 10 = 90 > 22.5
    # 160 s² - 80 s - 12.5 = 0  ->  s = (80 + sqrt(6400 + 8000)) / 320 = (80 + 120) / 320 = 0.625
    assert power_limit_scale(MODEL, braking, SPEEDS, 22.5) == pytest.approx(0.625)


def test_when_limit_below_static_power_expect_scale_zero():
    # 4 W < 5 W static: no torque can be afforded.
    assert power_limit_scale(MODEL, DRIVE, SPEEDS, 4.0) == 0.0


def test_when_speed_losses_exceed_limit_while_driving_expect_scale_zero():
    fast = (20.0, 20.0, 20.0, 20.0)
    # c0 = 0.05 * 1600 + 5 = 85 > 22.5 already at s = 0, and driving (b = 80 > 0) only adds.
    assert power_limit_scale(MODEL, DRIVE, fast, 22.5) == 0.0


def test_when_speed_losses_exceed_limit_while_braking_expect_least_power_braking():
    model = ChassisPowerModel(k1=10.0, k2=0.05, static_power_w=5.0)
    braking = (-5.0, -5.0, -5.0, -5.0)
    fast = (20.0, 20.0, 20.0, 20.0)
    # a = 10 * 100 = 1000, b = -4 * 100 = -400, c0 = 85. Least P(s) is at the vertex
    # s = 400 / 2000 = 0.2: P = 40 - 80 + 85 = 45 W, still above 22.5 W but below P(0) = 85.
    assert power_limit_scale(model, braking, fast, 22.5) == pytest.approx(0.2)


def test_when_no_copper_loss_expect_linear_solution():
    model = ChassisPowerModel(k1=0.0, k2=0.05, static_power_w=5.0)
    # P(s) = 20 s + 10 = 22.5  ->  s = 0.625
    assert power_limit_scale(model, DRIVE, SPEEDS, 22.5) == pytest.approx(0.625)


def test_when_no_copper_loss_and_braking_over_limit_expect_full_braking():
    model = ChassisPowerModel(k1=0.0, k2=0.05, static_power_w=5.0)
    fast = (20.0, 20.0, 20.0, 20.0)
    # P(s) = -80 * 0.1 s + 85 = 85 - 8 s > 22.5 for all s; least at s = 1.
    assert power_limit_scale(model, (-0.1, -0.1, -0.1, -0.1), fast, 22.5) == 1.0


def test_when_all_torques_zero_expect_nothing_to_scale():
    assert power_limit_scale(MODEL, (0.0, 0.0, 0.0, 0.0), SPEEDS, 0.0) == 1.0


def test_when_limit_infinite_expect_scale_one():
    assert power_limit_scale(MODEL, (100.0,) * 4, (100.0,) * 4, math.inf) == 1.0


@pytest.mark.parametrize(
    ('torques', 'speeds', 'limit', 'message'),
    [
        ((1.0, math.nan), (1.0, 1.0), 10.0, 'finite'),
        ((1.0, 1.0), (1.0, math.inf), 10.0, 'finite'),
        ((1.0, 1.0), (1.0,), 10.0, 'one speed per torque'),
        ((1.0,), (1.0,), -1.0, 'power limit'),
        ((1.0,), (1.0,), math.nan, 'power limit'),
    ],
)
def test_when_input_invalid_expect_rejected(torques, speeds, limit, message):
    with pytest.raises(InputRejectedError, match=message):
        power_limit_scale(MODEL, torques, speeds, limit)


@pytest.mark.parametrize('field', ['k1', 'k2', 'static_power_w'])
@pytest.mark.parametrize('value', [-1.0, math.nan, math.inf, True])
def test_when_model_coefficient_invalid_expect_config_error(field, value):
    values = {'k1': 1.0, 'k2': 1.0, 'static_power_w': 1.0, field: value}
    with pytest.raises(ConfigError, match=field):
        ChassisPowerModel(**values)


torque = st.floats(min_value=-20.0, max_value=20.0)
speed = st.floats(min_value=-100.0, max_value=100.0)
models = st.builds(
    ChassisPowerModel,
    k1=st.floats(min_value=0.0, max_value=10.0),
    k2=st.floats(min_value=0.0, max_value=0.05),
    static_power_w=st.floats(min_value=0.0, max_value=20.0),
)


def _power(model, torques, speeds, s):
    return estimate_power(model, [s * t for t in torques], speeds)


@given(
    models,
    st.lists(st.tuples(torque, speed), min_size=1, max_size=6),
    st.floats(min_value=0.0, max_value=500.0),
)
def test_invariant_scaled_power_within_limit_whenever_some_scale_is(model, wheels, limit):
    torques = [t for t, _ in wheels]
    speeds = [w for _, w in wheels]
    s = power_limit_scale(model, torques, speeds, limit)
    assert 0.0 <= s <= 1.0
    # P(s) is a convex quadratic, so its least value on [0, 1] is at 0, 1 or the vertex;
    # a feasible s exists iff that least value is within the limit.
    a = model.k1 * sum(t * t for t in torques)
    b = sum(t * w for t, w in wheels)
    candidates = [0.0, 1.0] + ([min(1.0, max(0.0, -b / (2 * a)))] if a > 0 else [])
    least = min(_power(model, torques, speeds, c) for c in candidates)
    scale_of_terms = 1.0 + abs(b) + a + model.k2 * sum(w * w for w in speeds) + limit
    tolerance = 1e-9 * scale_of_terms
    if least <= limit and model.static_power_w <= limit:
        assert _power(model, torques, speeds, s) <= limit + tolerance
        # ... and s is the largest such factor.
        if s < 1.0:
            assert _power(model, torques, speeds, min(1.0, s + 1e-6)) > limit - tolerance


def test_when_fitting_noise_free_samples_expect_coefficients_recovered():
    rng = np.random.default_rng(7)
    torques = rng.uniform(-3.0, 3.0, size=(200, 4))
    speeds = rng.uniform(-60.0, 60.0, size=(200, 4))
    truth = ChassisPowerModel(k1=2.96, k2=3.08e-3, static_power_w=2.7)
    power = [estimate_power(truth, t, w) for t, w in zip(torques, speeds, strict=True)]
    fitted = fit_power_model(torques, speeds, power)
    assert fitted.k1 == pytest.approx(2.96, rel=1e-9)
    assert fitted.k2 == pytest.approx(3.08e-3, rel=1e-9)
    assert fitted.static_power_w == pytest.approx(2.7, rel=1e-9)


def test_when_fitting_samples_that_never_vary_expect_rejected():
    torques = np.ones((10, 4))
    speeds = np.ones((10, 4))
    with pytest.raises(InputRejectedError, match='do not separate'):
        fit_power_model(torques, speeds, np.full(10, 20.0))


def test_when_fit_gives_negative_coefficient_expect_rejected():
    rng = np.random.default_rng(3)
    torques = rng.uniform(-3.0, 3.0, size=(50, 4))
    speeds = rng.uniform(-60.0, 60.0, size=(50, 4))
    # A meter reading 10 W low: the static term fits to -10 W.
    power = np.sum(torques * speeds, axis=1) - 10.0
    with pytest.raises(InputRejectedError, match='negative coefficient'):
        fit_power_model(torques, speeds, power)


def test_when_fit_shapes_disagree_expect_rejected():
    with pytest.raises(InputRejectedError, match='shape'):
        fit_power_model(np.ones((5, 4)), np.ones((5, 3)), np.ones(5))
