import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.errors import InputRejectedError
from rm_base.geometry import shortest_angular_distance, wrap_to_2pi, wrap_to_pi

angles = st.floats(min_value=-1e6, max_value=1e6)


def test_when_angle_in_range_expect_unchanged():
    assert wrap_to_pi(1.0) == 1.0


def test_when_angle_above_pi_expect_wrapped_negative():
    # 3pi/2 - 2pi = -pi/2
    assert wrap_to_pi(1.5 * math.pi) == pytest.approx(-0.5 * math.pi)


def test_when_angle_below_minus_pi_expect_wrapped_positive():
    # -3pi/2 + 2pi = +pi/2
    assert wrap_to_pi(-1.5 * math.pi) == pytest.approx(0.5 * math.pi)


def test_when_angle_is_pi_expect_minus_pi():
    # The range is half-open, [-pi, pi): +pi is the same angle as -pi
    assert wrap_to_pi(math.pi) == -math.pi


def test_when_angle_many_turns_expect_remainder():
    # 10 turns + 0.25 rad
    assert wrap_to_pi(10 * 2 * math.pi + 0.25) == pytest.approx(0.25)


def test_when_negative_angle_wrapped_to_2pi_expect_positive():
    # -pi/2 + 2pi = 3pi/2
    assert wrap_to_2pi(-0.5 * math.pi) == pytest.approx(1.5 * math.pi)


def test_when_angle_is_2pi_expect_zero():
    assert wrap_to_2pi(2.0 * math.pi) == 0.0


def test_when_tiny_negative_wrapped_to_2pi_expect_in_range():
    # -1e-17 + 2pi rounds to exactly 2pi, which is outside [0, 2pi)
    assert 0.0 <= wrap_to_2pi(-1e-17) < 2.0 * math.pi


def test_when_going_across_pi_ccw_expect_short_positive_distance():
    # from 170° to -170° the short way is +20° through 180°
    assert shortest_angular_distance(math.radians(170), math.radians(-170)) == pytest.approx(
        math.radians(20)
    )


def test_when_going_across_pi_cw_expect_short_negative_distance():
    # from -170° to 170° the short way is -20°
    assert shortest_angular_distance(math.radians(-170), math.radians(170)) == pytest.approx(
        math.radians(-20)
    )


@pytest.mark.parametrize('function', [wrap_to_pi, wrap_to_2pi])
@pytest.mark.parametrize('value', [math.nan, math.inf, -math.inf])
def test_when_angle_not_finite_expect_rejected(function, value):
    with pytest.raises(InputRejectedError, match='finite'):
        function(value)


@given(angles)
def test_when_wrapped_to_pi_expect_in_range_and_same_direction(angle):
    wrapped = wrap_to_pi(angle)
    assert -math.pi <= wrapped < math.pi
    assert math.cos(wrapped) == pytest.approx(math.cos(angle), abs=1e-9)
    assert math.sin(wrapped) == pytest.approx(math.sin(angle), abs=1e-9)


@given(angles)
def test_when_wrapped_to_2pi_expect_in_range_and_same_direction(angle):
    wrapped = wrap_to_2pi(angle)
    assert 0.0 <= wrapped < 2.0 * math.pi
    assert math.cos(wrapped) == pytest.approx(math.cos(angle), abs=1e-9)
    assert math.sin(wrapped) == pytest.approx(math.sin(angle), abs=1e-9)


@given(angles, angles)
def test_when_distance_added_to_start_expect_end_angle(start, end):
    distance = shortest_angular_distance(start, end)
    assert -math.pi <= distance < math.pi
    assert wrap_to_pi(start + distance - end) == pytest.approx(0.0, abs=1e-9)
