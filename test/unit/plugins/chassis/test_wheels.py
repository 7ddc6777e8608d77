"""Wheel speed loops and the chassis power limit."""

import math

import pytest
from rm_base.control import ChassisPowerModel, PidGains, estimate_power
from rm_base.errors import InputRejectedError
from rm_plugins.chassis import SpeedPredictor, WheelSpeedController

MODEL = ChassisPowerModel(k1=3.0, k2=0.0, static_power_w=2.0)
GAINS = PidGains(kp=1.0, output_limit=4.0)


def test_when_unlimited_expect_the_pid_efforts_unscaled():
    wheels = WheelSpeedController(4, GAINS, MODEL)
    out = wheels.update([10.0, -10.0, 1.0, 0.0], [9.0, -9.0, 0.0, 0.0], 0.01, math.inf)
    # kp * error = 1, -1, 1, 0 N*m.
    assert out.efforts == pytest.approx((1.0, -1.0, 1.0, 0.0))
    assert out.scale == 1.0
    # P = k1 * sum(tau^2) + sum(tau * w) + static = 3 * 3 + (9 + 9 + 0) + 2 = 29 W.
    assert out.power_w == pytest.approx(29.0)


def test_when_the_limit_binds_expect_one_common_scale_and_power_at_the_limit():
    wheels = WheelSpeedController(4, GAINS, MODEL)
    # Hard acceleration: every wheel asks for the 4 N*m maximum at 10 rad/s.
    out = wheels.update([40.0] * 4, [10.0] * 4, 0.01, 60.0)
    # Requested: 3 * 64 + 160 + 2 = 354 W; scaled: 192 s^2 + 160 s + 2 = 60 W.
    assert out.requested_power_w == pytest.approx(354.0)
    assert out.power_w == pytest.approx(60.0)
    assert out.scale == pytest.approx((-160.0 + math.sqrt(160.0**2 + 4 * 192 * 58)) / 384)
    assert len(set(out.efforts)) == 1  # one factor for all: same direction of force
    assert estimate_power(MODEL, out.efforts, [10.0] * 4) == pytest.approx(60.0)


def test_when_inputs_are_bad_expect_rejected():
    wheels = WheelSpeedController(4, GAINS, MODEL)
    with pytest.raises(InputRejectedError, match='need 4'):
        wheels.update([1.0] * 3, [0.0] * 4, 0.01, 60.0)
    with pytest.raises(InputRejectedError, match='finite'):
        wheels.update([math.nan] * 4, [0.0] * 4, 0.01, 60.0)
    with pytest.raises(InputRejectedError, match='power limit'):
        wheels.update([0.0] * 4, [0.0] * 4, 0.01, -1.0)


def test_when_the_power_speeds_are_higher_expect_the_limit_met_at_those_speeds():
    wheels = WheelSpeedController(4, GAINS, MODEL)
    # Measured 10 rad/s, predicted 15 rad/s at the end of the period: the efforts are
    # scaled for 15 rad/s, so they stay under the limit while the wheels speed up.
    out = wheels.update([40.0] * 4, [10.0] * 4, 0.01, 60.0, [15.0] * 4)
    assert estimate_power(MODEL, out.efforts, [15.0] * 4) == pytest.approx(60.0)
    assert estimate_power(MODEL, out.efforts, [10.0] * 4) < 60.0


def test_when_speeds_change_expect_the_predictor_to_extrapolate_them():
    predictor = SpeedPredictor(max_lead=0.05)
    assert predictor.predict(0) == ()
    predictor.update(0, [1.0, -2.0])
    assert predictor.predict(10_000_000) == (1.0, -2.0)  # one sample: no acceleration yet
    predictor.update(5_000_000, [1.5, -2.0])  # +100 rad/s^2 on the first wheel
    predictor.update(5_000_000, [9.0, 9.0])  # the same sample again: ignored
    # 10 ms after the last sample: 1.5 + 100 * 0.01 = 2.5 rad/s.
    assert predictor.predict(15_000_000) == pytest.approx((2.5, -2.0))
    # Never further ahead than max_lead (50 ms): 1.5 + 100 * 0.05 = 6.5 rad/s.
    assert predictor.predict(1_000_000_000) == pytest.approx((6.5, -2.0))
    # A gap longer than max_lead says nothing about the acceleration.
    predictor.update(500_000_000, [3.0, -2.0])
    assert predictor.predict(510_000_000) == (3.0, -2.0)
