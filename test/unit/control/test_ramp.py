import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.control import RampLimiter, RampLimits, ramp_step
from rm_base.errors import ConfigError, InputRejectedError

# launch 1, normal 4, brake 10 u/s^2; launch below |v| = 0.5 u. With dt = 0.1 s the
# largest steps are launch 0.1, normal 0.4, brake 1.0.
LIMITS = RampLimits(
    launch_acceleration=1.0, normal_acceleration=4.0, brake_acceleration=10.0, launch_speed=0.5
)


def test_when_starting_from_rest_expect_launch_acceleration():
    # |0| < 0.5: launch: 0 + 1 * 0.1 = 0.1
    assert ramp_step(0.0, 3.0, LIMITS, 0.1) == pytest.approx(0.1)


def test_when_starting_from_rest_backwards_expect_launch_acceleration():
    # 0 - 1 * 0.1 = -0.1
    assert ramp_step(0.0, -3.0, LIMITS, 0.1) == pytest.approx(-0.1)


def test_when_speeding_up_above_launch_speed_expect_normal_acceleration():
    # |1| >= 0.5, speeding up: 1 + 4 * 0.1 = 1.4
    assert ramp_step(1.0, 3.0, LIMITS, 0.1) == pytest.approx(1.4)


def test_when_at_launch_speed_expect_normal_acceleration():
    # |0.5| is not below 0.5: normal: 0.5 + 0.4 = 0.9
    assert ramp_step(0.5, 3.0, LIMITS, 0.1) == pytest.approx(0.9)


def test_when_slowing_down_expect_brake_acceleration():
    # |0.5| < |2|, same sign: brake: 2 - 10 * 0.1 = 1.0
    assert ramp_step(2.0, 0.5, LIMITS, 0.1) == pytest.approx(1.0)


def test_when_slowing_down_backwards_expect_brake_acceleration():
    # -2 + 10 * 0.1 = -1.0
    assert ramp_step(-2.0, -0.5, LIMITS, 0.1) == pytest.approx(-1.0)


def test_when_target_within_one_step_expect_target_exactly():
    # brake step would be 1.0, only 0.5 is needed
    assert ramp_step(2.0, 1.5, LIMITS, 0.1) == 1.5


def test_when_reversing_fast_expect_brake_only():
    # 2 -> -3: brake towards 0: 2 - 10 * 0.1 = 1.0 (still forward, not yet at zero)
    assert ramp_step(2.0, -3.0, LIMITS, 0.1) == pytest.approx(1.0)


def test_when_reversing_slowly_expect_brake_to_zero_then_launch():
    # 0.5 -> -3: braking to 0 takes 0.5 / 10 = 0.05 s; the other 0.05 s launches at 1:
    # 0 - 1 * 0.05 = -0.05
    assert ramp_step(0.5, -3.0, LIMITS, 0.1) == pytest.approx(-0.05)


def test_when_phase_unlimited_expect_jump_to_target():
    limits = RampLimits(launch_acceleration=1.0, normal_acceleration=None, launch_speed=0.5)
    # normal phase (|1| >= 0.5), unlimited: straight to 3
    assert ramp_step(1.0, 3.0, limits, 0.1) == 3.0


def test_when_brake_unlimited_and_reversing_expect_instant_stop_then_launch():
    limits = RampLimits(launch_acceleration=1.0, normal_acceleration=4.0, launch_speed=0.5)
    # brake to 0 takes no time, launch for the whole step: -1 * 0.1 = -0.1
    assert ramp_step(2.0, -3.0, limits, 0.1) == pytest.approx(-0.1)


def test_when_acceleration_inf_expect_same_as_none():
    assert RampLimits(normal_acceleration=math.inf).normal_acceleration is None


def test_when_axes_mixed_expect_each_limited_on_its_own():
    # vx and vy launch at 1 -> +-0.1; wz has no limits and passes 5 through
    limiter = RampLimiter([LIMITS, LIMITS, None])
    assert limiter.update((3.0, -3.0, 5.0), 0.1) == pytest.approx((0.1, -0.1, 5.0))


def test_when_updated_repeatedly_expect_launch_then_normal_phase():
    limiter = RampLimiter([LIMITS])
    # launch: 0.1, 0.2, 0.3, 0.4, 0.5; then |0.5| >= 0.5: normal: 0.9, 1.3
    values = [limiter.update([3.0], 0.1)[0] for _ in range(7)]
    assert values == pytest.approx([0.1, 0.2, 0.3, 0.4, 0.5, 0.9, 1.3])


def test_when_reset_to_values_expect_ramp_from_there():
    limiter = RampLimiter([LIMITS])
    limiter.reset([2.0])
    # brake from 2: 2 - 1 = 1
    assert limiter.update([0.0], 0.1) == pytest.approx((1.0,))


def test_when_target_count_wrong_expect_rejected():
    limiter = RampLimiter([LIMITS, LIMITS])
    with pytest.raises(InputRejectedError, match='expected 2'):
        limiter.update([1.0], 0.1)


def test_when_target_nan_expect_rejected_and_state_kept():
    limiter = RampLimiter([LIMITS])
    limiter.update([3.0], 0.1)  # 0.1
    with pytest.raises(InputRejectedError, match='finite'):
        limiter.update([math.nan], 0.1)
    assert limiter.values == pytest.approx((0.1,))


@pytest.mark.parametrize('dt', [0.0, -0.1, math.nan])
def test_when_dt_invalid_expect_rejected(dt):
    with pytest.raises(InputRejectedError, match='dt'):
        RampLimiter([LIMITS]).update([1.0], dt)


@pytest.mark.parametrize(
    ('field', 'value'),
    [('launch_acceleration', 0.0), ('brake_acceleration', -1.0), ('launch_speed', math.inf)],
)
def test_when_limit_invalid_expect_config_error(field, value):
    with pytest.raises(ConfigError, match=field):
        RampLimits(**{field: value})


def test_when_no_axes_expect_config_error():
    with pytest.raises(ConfigError, match='at least one axis'):
        RampLimiter([])


speeds = st.floats(min_value=-10.0, max_value=10.0)


@given(current=speeds, target=speeds, dt=st.floats(min_value=1e-4, max_value=0.5))
def test_when_stepping_expect_never_past_target_nor_faster_than_largest_limit(current, target, dt):
    new = ramp_step(current, target, LIMITS, dt)
    assert min(current, target) <= new <= max(current, target)
    # Even a reversal (brake then launch) spends at most dt at up to the largest limit 10.
    assert abs(new - current) <= 10.0 * dt + 1e-12
