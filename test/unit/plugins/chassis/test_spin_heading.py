"""SpinHeadingLoop: GYRO's heading follows the spin asked for, within a bounded error."""

import math

import pytest
from rm_base.errors import ConfigError, InputRejectedError
from rm_plugins.chassis.spin_heading import SpinHeadingLoop, SpinHeadingParams

DT = 0.005  # [s]


def test_the_first_step_takes_the_measured_heading_as_the_start():
    loop = SpinHeadingLoop(SpinHeadingParams(gain=5.0))
    assert loop.update(6.0, 1.0, DT) == 6.0
    assert loop.error == 0.0


def test_a_heading_that_lags_the_spin_asked_for_raises_the_rate_by_gain_times_the_lag():
    loop = SpinHeadingLoop(SpinHeadingParams(gain=5.0, max_error=0.5))
    loop.update(6.0, 0.0, DT)
    # the reference moved 6 rad/s * 5 ms = 0.03 rad; the chassis turned 0.02
    assert loop.update(6.0, 0.02, DT) == pytest.approx(6.0 + 5.0 * 0.01)
    assert loop.error == pytest.approx(0.01)
    # ahead of it: slower
    assert loop.update(6.0, 0.08, DT) == pytest.approx(6.0 + 5.0 * (0.06 - 0.08))


def test_the_reference_advances_by_the_rate_asked_in_the_step_before():
    loop = SpinHeadingLoop(SpinHeadingParams(gain=1.0))
    loop.update(2.0, 0.0, DT)
    loop.update(4.0, 0.0, DT)  # the reference moves by the 2 rad/s of the step before
    assert loop.error == pytest.approx(2.0 * DT)
    loop.update(4.0, 0.0, DT)
    assert loop.error == pytest.approx(6.0 * DT)


def test_the_error_is_wrapped_across_pi():
    loop = SpinHeadingLoop(SpinHeadingParams(gain=5.0))
    loop.update(6.0, math.pi - 0.01, DT)
    # the chassis crossed pi (its heading is reported wrapped) and lags by 0.01 rad
    loop.update(6.0, -math.pi + 0.01, DT)
    assert loop.error == pytest.approx(0.01)


def test_a_held_chassis_does_not_wind_the_loop_up():
    loop = SpinHeadingLoop(SpinHeadingParams(gain=5.0, max_error=0.3))
    loop.update(6.0, 0.0, DT)
    for _ in range(400):  # 2 s against a wall: the heading stays at 0
        wz = loop.update(6.0, 0.0, DT)
    assert loop.error == pytest.approx(0.3)
    assert wz == pytest.approx(6.0 + 5.0 * 0.3)  # at most gain * max_error on top
    # released, the chassis makes up no more than max_error: once it turned 0.3 rad more
    # than the spin asked since, the correction is gone
    heading = 0.0
    for _ in range(300):  # 1.5 s, 7.5 time constants of 1 / gain
        heading += loop.update(6.0, heading, DT) * DT
    assert abs(loop.error) < 0.001
    assert heading - 6.0 * 300 * DT == pytest.approx(0.3, abs=0.002)


def test_against_a_dragging_wheel_the_spin_rate_is_restored():
    # a plant that gives 75 % of the rate asked (a stopped wheel of four)
    loop = SpinHeadingLoop(SpinHeadingParams(gain=5.0, max_error=0.5))
    heading = 0.0
    for _ in range(2000):  # 10 s
        before = heading
        heading += 0.75 * loop.update(6.0, heading, DT) * DT
    assert (heading - before) / DT == pytest.approx(6.0, rel=1e-3)
    assert loop.error == pytest.approx(2.0 / 5.0, rel=1e-3)  # (6 / 0.75 - 6) / gain


def test_gain_zero_is_the_open_loop():
    loop = SpinHeadingLoop(SpinHeadingParams(gain=0.0))
    loop.update(6.0, 0.0, DT)
    assert loop.update(6.0, -1.0, DT) == 6.0


def test_reset_starts_again_from_the_measured_heading():
    loop = SpinHeadingLoop(SpinHeadingParams(gain=5.0))
    loop.update(6.0, 0.0, DT)
    loop.update(6.0, 0.0, DT)
    loop.reset()
    assert loop.error == 0.0
    assert loop.update(6.0, 2.0, DT) == 6.0


@pytest.mark.parametrize(('rate', 'heading', 'dt'), [
    (math.nan, 0.0, DT), (6.0, math.inf, DT), (6.0, 0.0, 0.0), (6.0, 0.0, math.nan),
])
def test_a_value_that_is_not_finite_is_rejected(rate, heading, dt):
    with pytest.raises(InputRejectedError):
        SpinHeadingLoop(SpinHeadingParams(gain=5.0)).update(rate, heading, dt)


@pytest.mark.parametrize('kwargs', [{'gain': -1.0}, {'max_error': 0.0}, {'gain': math.nan}])
def test_bad_parameters_are_refused(kwargs):
    with pytest.raises(ConfigError):
        SpinHeadingParams(**kwargs)
