import math

import pytest
from rm_base.control import IncrementalPid, IncrementalPidGains, TdParams
from rm_base.errors import ConfigError, InputRejectedError


def test_when_first_update_expect_previous_error_taken_as_zero():
    pid = IncrementalPid(IncrementalPidGains(kp=2.0, ki=10.0))
    # e = 1, e_prev = 0: du = 2 * (1 - 0) + 10 * 1 * 0.01 = 2 + 0.1 = 2.1
    assert pid.update(1.0, 0.0, 0.01) == pytest.approx(2.1)


def test_when_error_constant_expect_only_integral_increment():
    pid = IncrementalPid(IncrementalPidGains(kp=2.0, ki=10.0))
    pid.update(1.0, 0.0, 0.01)  # 2.1, as above
    # e = 1 again: du = 2 * (1 - 1) + 10 * 1 * 0.01 = 0.1 -> 2.2
    assert pid.update(1.0, 0.0, 0.01) == pytest.approx(2.2)
    assert pid.last_increment == pytest.approx(0.1)


def test_when_error_steps_expect_single_derivative_pulse():
    pid = IncrementalPid(IncrementalPidGains(kd=0.01))
    pid.update(0.0, 0.0, 0.01)  # e = 0, no derivative on the first update
    # e: 0 -> 1: de/dt = 100, previous 0: du = 0.01 * (100 - 0) = 1.0
    assert pid.update(1.0, 0.0, 0.01) == pytest.approx(1.0)
    # e stays 1: de/dt = 0: du = 0.01 * (0 - 100) = -1.0 -> back to 0 (a D term of kd * de/dt)
    assert pid.update(1.0, 0.0, 0.01) == pytest.approx(0.0)


def test_when_output_reaches_limit_expect_clamped_without_windup():
    pid = IncrementalPid(IncrementalPidGains(ki=100.0, output_limit=25.0))
    # du = 100 * 1 * 0.1 = 10 per update: 10, 20, 30 -> 25, 35 -> 25
    for expected in (10.0, 20.0, 25.0, 25.0):
        assert pid.update(1.0, 0.0, 0.1) == pytest.approx(expected)
    # e = -1: du = -10 from the clamped 25 (not from 40): 15
    assert pid.update(-1.0, 0.0, 0.1) == pytest.approx(15.0)


def test_when_setpoint_td_expect_first_step_starts_at_measurement():
    pid = IncrementalPid(IncrementalPidGains(kp=1.0), setpoint_td=TdParams(100.0))
    # TD starts at the measurement 0 with x2 = 0: x1 = 0 + 0.001 * 0 = 0, so e = 0 and
    # the unit setpoint step does not reach the output yet.
    assert pid.update(1.0, 0.0, 0.001) == 0.0
    assert pid.tracked_setpoint == 0.0


def test_when_setpoint_td_expect_setpoint_ramps_at_acceleration_limit():
    pid = IncrementalPid(IncrementalPidGains(kp=1.0), setpoint_td=TdParams(100.0))
    pid.update(1.0, 0.0, 0.001)
    # First step: far from the target, fhan = +r = 100, so x2 = 0 + 0.001 * 100 = 0.1.
    # Second step: x1 = 0 + 0.001 * 0.1 = 1e-4; e = 1e-4; du = 1 * (1e-4 - 0) = 1e-4.
    assert pid.update(1.0, 0.0, 0.001) == pytest.approx(1e-4)
    assert pid.tracked_setpoint == pytest.approx(1e-4)


def test_when_no_td_expect_no_tracked_setpoint():
    pid = IncrementalPid(IncrementalPidGains(kp=1.0))
    pid.update(1.0, 0.0, 0.001)
    assert pid.tracked_setpoint is None


def test_when_reset_expect_output_zero_and_td_restarts_at_measurement():
    pid = IncrementalPid(IncrementalPidGains(kp=1.0), setpoint_td=TdParams(100.0))
    for _ in range(100):
        pid.update(1.0, 0.0, 0.001)
    pid.reset()
    assert pid.output == 0.0
    # As after construction: the TD starts at the new measurement 0.5, e = 0
    assert pid.update(1.0, 0.5, 0.001) == 0.0
    assert pid.tracked_setpoint == 0.5


@pytest.mark.parametrize(
    ('setpoint', 'measurement', 'dt'),
    [(math.nan, 0.0, 0.001), (0.0, math.inf, 0.001), (0.0, 0.0, 0.0), (0.0, 0.0, -1.0)],
)
def test_when_input_invalid_expect_rejected(setpoint, measurement, dt):
    pid = IncrementalPid(IncrementalPidGains(kp=1.0))
    with pytest.raises(InputRejectedError):
        pid.update(setpoint, measurement, dt)


def test_when_gain_negative_expect_config_error():
    with pytest.raises(ConfigError, match='ki'):
        IncrementalPidGains(ki=-1.0)


def test_when_output_limit_zero_expect_config_error():
    with pytest.raises(ConfigError, match='output_limit'):
        IncrementalPidGains(output_limit=0.0)


def test_in_angle_mode_the_error_turns_the_short_way_and_its_rate_has_no_wrap_spike():
    pid = IncrementalPid(IncrementalPidGains(kp=1.0, kd=0.01, angle_mode=True))
    # From 3.0 rad to -3.0 rad: the short way is +0.283 rad across pi, not -6 rad.
    assert pid.update(-3.0, 3.0, 0.001) == pytest.approx(2.0 * math.pi - 6.0)
    # The error crosses -pi to +pi (measurement moves 0.02 rad): wrapped, the change is
    # -0.02 rad, so the D increment is small, not a 2*pi/dt kick.
    pid = IncrementalPid(IncrementalPidGains(kp=0.0, kd=0.001, angle_mode=True))
    pid.update(0.0, math.pi - 0.01, 0.001)
    out = pid.update(0.0, -math.pi + 0.01, 0.001)
    assert abs(out) < 0.05
    positional = IncrementalPid(IncrementalPidGains(kp=1.0))
    assert positional.update(2.0 * math.pi, 0.0, 0.001) == pytest.approx(2.0 * math.pi)


def test_in_angle_mode_the_td_follows_the_setpoint_the_short_way_round():
    pid = IncrementalPid(IncrementalPidGains(kp=1.0, angle_mode=True), setpoint_td=TdParams(50.0))
    pid.update(3.0, 3.0, 0.001)
    for _ in range(2000):
        pid.update(-3.0, 3.0, 0.001)  # 0.28 rad ahead across +pi, not 6 rad back
    tracked = pid.tracked_setpoint
    assert tracked == pytest.approx(-3.0 + 2.0 * math.pi, abs=1e-3)
