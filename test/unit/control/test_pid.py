import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.control import Pid, PidGains
from rm_base.errors import ConfigError, InputRejectedError

finite = st.floats(min_value=-1e3, max_value=1e3)


def test_when_only_kp_expect_output_is_kp_times_error():
    pid = Pid(PidGains(kp=2.0))
    # e = 1.0 - 0.5 = 0.5; P = 2 * 0.5 = 1.0
    assert pid.update(setpoint=1.0, measurement=0.5, dt=0.01) == pytest.approx(1.0)


def test_when_first_update_expect_error_integrated_as_constant_over_dt():
    pid = Pid(PidGains(ki=1.0))
    # First update: no previous error, so both trapezoid ends are e = 0.5:
    # I = 1 * (0.5 + 0.5) / 2 * 0.01 = 0.005
    assert pid.update(1.0, 0.5, 0.01) == pytest.approx(0.005)


def test_when_error_changes_expect_trapezoidal_integral():
    pid = Pid(PidGains(ki=10.0))
    pid.update(1.0, 0.0, 0.1)  # I = 10 * (1 + 1) / 2 * 0.1 = 1.0
    # e: 1 -> 3; I = 1.0 + 10 * (1 + 3) / 2 * 0.1 = 1.0 + 2.0 = 3.0
    # (a rectangle rule on the new error would give 1.0 + 3.0 = 4.0)
    assert pid.update(3.0, 0.0, 0.1) == pytest.approx(3.0)


def test_when_setpoint_steps_expect_no_derivative_kick():
    pid = Pid(PidGains(kp=1.0, kd=1.0))
    pid.update(0.0, 0.0, 0.001)
    # Measurement unchanged, so dm/dt = 0 and D = 0 however large the setpoint step;
    # the output is P alone: 1 * (5 - 0) = 5.
    assert pid.update(5.0, 0.0, 0.001) == pytest.approx(5.0)
    assert pid.d_term == 0.0


def test_when_measurement_rises_expect_derivative_opposes_it():
    pid = Pid(PidGains(kd=0.5))
    pid.update(0.0, 0.0, 0.001)
    # dm/dt = (0.01 - 0) / 0.001 = 10; D = -0.5 * 10 = -5. P and I are off (kp = ki = 0).
    assert pid.update(0.0, 0.01, 0.001) == pytest.approx(-5.0)


def test_when_derivative_filtered_expect_first_order_response_to_rate_step():
    pid = Pid(PidGains(kd=1.0, derivative_tau_s=0.01))
    pid.update(0.0, 0.0, 0.01)
    # Raw rate (0.1 - 0) / 0.01 = 10. One step of dt = tau through the low-pass from 0:
    # rate = 10 * (1 - exp(-0.01 / 0.01)) = 10 * 0.6321206 = 6.321206; D = -6.321206
    assert pid.update(0.0, 0.1, 0.01) == pytest.approx(-6.321206, rel=1e-6)


def test_when_first_update_expect_no_derivative():
    pid = Pid(PidGains(kd=100.0))
    # No previous measurement: the rate is unknown and taken as 0.
    assert pid.update(0.0, 123.0, 0.001) == pytest.approx(0.0)


def test_when_output_exceeds_limit_expect_clamped_positive():
    pid = Pid(PidGains(kp=100.0, output_limit=10.0))
    # P = 100 * 1 = 100 > 10
    assert pid.update(1.0, 0.0, 0.001) == 10.0


def test_when_output_exceeds_limit_expect_clamped_negative():
    pid = Pid(PidGains(kp=100.0, output_limit=10.0))
    # P = 100 * -1 = -100 < -10
    assert pid.update(-1.0, 0.0, 0.001) == -10.0


def test_when_integral_exceeds_limit_expect_i_term_clamped():
    pid = Pid(PidGains(ki=100.0, integral_limit=3.0))
    pid.update(1.0, 0.0, 0.1)  # I = 100 * 1 * 0.1 = 10 -> clamped to 3
    pid.update(1.0, 0.0, 0.1)  # I = 3 + 10 = 13 -> clamped to 3
    assert pid.i_term == 3.0


def test_when_error_reverses_after_saturation_expect_integral_unwinds_at_once():
    pid = Pid(PidGains(ki=100.0, integral_limit=3.0))
    for _ in range(5):
        pid.update(1.0, 0.0, 0.1)  # held at 3 (would be 50 without the limit)
    # e: +1 -> -1: I = 3 + 100 * (1 - 1) / 2 * 0.1 = 3; next e = -1:
    # I = 3 + 100 * (-1 - 1) / 2 * 0.1 = 3 - 10 = -7 -> clamped to -3
    pid.update(-1.0, 0.0, 0.1)
    assert pid.i_term == pytest.approx(3.0)
    pid.update(-1.0, 0.0, 0.1)
    assert pid.i_term == -3.0


def test_when_no_integral_limit_expect_output_limit_bounds_i_term():
    pid = Pid(PidGains(ki=100.0, output_limit=2.0))
    # I = 100 * 1 * 0.1 = 10, bounded by the output limit 2 (integral_limit is inf)
    pid.update(1.0, 0.0, 0.1)
    assert pid.i_term == 2.0


def test_when_error_outside_integral_separation_expect_no_integration():
    pid = Pid(PidGains(kp=1.0, ki=1.0, integral_separation=1.0))
    # |e| = 2 >= 1: I stays 0, output is P = 1 * 2 = 2
    assert pid.update(2.0, 0.0, 0.1) == pytest.approx(2.0)
    assert pid.i_term == 0.0


def test_when_error_enters_integral_separation_band_expect_only_new_error_integrated():
    pid = Pid(PidGains(ki=1.0, integral_separation=1.0))
    pid.update(2.0, 0.0, 0.1)  # outside the band: I = 0
    # Inside now (e = 0.5). The previous e = 2 was outside, so the trapezoid uses 0.5 at
    # both ends: I = 1 * (0.5 + 0.5) / 2 * 0.1 = 0.05 (not (2 + 0.5) / 2 * 0.1 = 0.125).
    assert pid.update(0.5, 0.0, 0.1) == pytest.approx(0.05)


def test_when_error_inside_deadband_expect_zero_output():
    pid = Pid(PidGains(kp=10.0, ki=10.0, deadband=0.1))
    # |e| = 0.05 <= 0.1 counts as 0: P = 0 and nothing integrates
    assert pid.update(0.05, 0.0, 0.01) == 0.0
    assert pid.i_term == 0.0


def test_when_error_outside_deadband_expect_full_error_used():
    pid = Pid(PidGains(kp=10.0, deadband=0.1))
    # |e| = 0.2 > 0.1: the whole error is used (the deadband is not subtracted):
    # P = 10 * 0.2 = 2.0
    assert pid.update(0.2, 0.0, 0.01) == pytest.approx(2.0)


def test_when_angle_error_wraps_positive_expect_shortest_way_negative():
    pid = Pid(PidGains(kp=1.0, angle_mode=True))
    # Raw e = 3 - (-3) = 6 rad; the shortest way is 6 - 2*pi = -0.2831853 rad (clockwise)
    assert pid.update(3.0, -3.0, 0.001) == pytest.approx(6.0 - 2.0 * math.pi)


def test_when_angle_error_wraps_negative_expect_shortest_way_positive():
    pid = Pid(PidGains(kp=1.0, angle_mode=True))
    # Raw e = -3 - 3 = -6 rad; the shortest way is -6 + 2*pi = +0.2831853 rad
    assert pid.update(-3.0, 3.0, 0.001) == pytest.approx(2.0 * math.pi - 6.0)


def test_when_angle_error_is_half_a_turn_expect_minus_pi():
    pid = Pid(PidGains(kp=1.0, angle_mode=True))
    # e = pi - 0 = pi: both ways are equally short; as wrap_to_pi, [-pi, pi) maps +pi to -pi
    assert pid.update(math.pi, 0.0, 0.001) == -math.pi


def test_when_not_angle_mode_expect_error_not_wrapped():
    pid = Pid(PidGains(kp=1.0))
    # e = 3 - (-3) = 6, as is
    assert pid.update(3.0, -3.0, 0.001) == pytest.approx(6.0)


def test_when_angle_measurement_crosses_pi_expect_derivative_of_short_step():
    pid = Pid(PidGains(kd=0.1, angle_mode=True))
    pid.update(math.pi - 0.01, math.pi - 0.01, 0.001)
    # Measurement jumps from pi - 0.01 to -pi + 0.01: a real move of +0.02 rad, so
    # dm/dt = 0.02 / 0.001 = 20 rad/s, D = -0.1 * 20 = -2.0 (error stays 0: setpoint =
    # measurement). Unwrapped, the step would look like -6.26 rad and D = +626.
    assert pid.update(-math.pi + 0.01, -math.pi + 0.01, 0.001) == pytest.approx(-2.0)


@pytest.mark.parametrize('dt', [0.0, -0.001, math.nan, math.inf])
def test_when_dt_not_positive_finite_expect_rejected(dt):
    pid = Pid(PidGains(kp=1.0))
    with pytest.raises(InputRejectedError, match='dt'):
        pid.update(1.0, 0.0, dt)


@pytest.mark.parametrize(
    ('setpoint', 'measurement'),
    [(math.nan, 0.0), (0.0, math.nan), (math.inf, 0.0), (0.0, -math.inf)],
)
def test_when_input_not_finite_expect_rejected(setpoint, measurement):
    pid = Pid(PidGains(kp=1.0))
    with pytest.raises(InputRejectedError, match='finite'):
        pid.update(setpoint, measurement, 0.001)


def test_when_input_rejected_expect_state_unchanged():
    pid = Pid(PidGains(kp=1.0, ki=1.0, kd=1.0))
    pid.update(1.0, 0.0, 0.1)  # I = 1 * 1 * 0.1 = 0.1
    with pytest.raises(InputRejectedError):
        pid.update(math.nan, 0.0, 0.1)
    # Same as if the NaN never came: e = 1 twice, I = 0.1 + 0.1 = 0.2, P = 1, D = 0
    assert pid.update(1.0, 0.0, 0.1) == pytest.approx(1.2)


def test_when_reset_expect_integral_and_history_cleared():
    pid = Pid(PidGains(ki=1.0, kd=1.0))
    pid.update(1.0, 0.0, 0.1)
    pid.reset()
    assert pid.i_term == 0.0
    assert pid.output == 0.0
    # No previous measurement after reset, so no derivative from 0 -> 5: output = I only,
    # I = 1 * 1 * 0.1 = 0.1 (e = 6 - 5 = 1, as a first update)
    assert pid.update(6.0, 5.0, 0.1) == pytest.approx(0.1)


def test_when_gains_replaced_expect_integral_kept_and_clamped():
    pid = Pid(PidGains(ki=10.0))
    pid.update(1.0, 0.0, 0.1)  # I = 10 * 1 * 0.1 = 1.0
    pid.gains = PidGains(ki=10.0, integral_limit=0.5)
    assert pid.i_term == 0.5


def test_when_terms_read_expect_they_sum_to_unclamped_output():
    pid = Pid(PidGains(kp=2.0, ki=1.0, kd=0.1))
    pid.update(0.0, 0.0, 0.1)
    output = pid.update(1.0, 0.5, 0.1)
    # P = 2 * 0.5 = 1; I = 1 * (0 + 0.5) / 2 * 0.1 = 0.025; D = -0.1 * 0.5 / 0.1 = -0.5
    assert (pid.p_term, pid.i_term, pid.d_term) == pytest.approx((1.0, 0.025, -0.5))
    assert output == pytest.approx(0.525)


@pytest.mark.parametrize(
    ('field', 'value'),
    [
        ('kp', -1.0),
        ('ki', math.nan),
        ('kd', math.inf),
        ('output_limit', 0.0),
        ('integral_limit', -1.0),
        ('integral_separation', 0.0),
        ('deadband', math.inf),
        ('derivative_tau_s', -0.1),
        ('kp', '1.0'),
    ],
)
def test_when_gain_invalid_expect_config_error(field, value):
    with pytest.raises(ConfigError, match=field):
        PidGains(**{field: value})


def test_when_angle_mode_not_bool_expect_config_error():
    with pytest.raises(ConfigError, match='angle_mode'):
        PidGains(angle_mode='false')


def test_when_gains_built_from_ints_expect_floats():
    assert isinstance(PidGains(kp=2).kp, float)


@given(
    setpoints=st.lists(finite, min_size=1, max_size=50),
    measurements=st.lists(finite, min_size=50, max_size=50),
    dt=st.floats(min_value=1e-4, max_value=0.1),
)
def test_when_inputs_finite_expect_output_finite_and_within_limit(setpoints, measurements, dt):
    pid = Pid(PidGains(kp=5.0, ki=50.0, kd=0.5, output_limit=3.0, derivative_tau_s=0.002))
    for setpoint, measurement in zip(setpoints, measurements, strict=False):
        output = pid.update(setpoint, measurement, dt)
        assert math.isfinite(output)
        assert -3.0 <= output <= 3.0
