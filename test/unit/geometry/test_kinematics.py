import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry import (
    Twist2D,
    Wheel,
    WheelKinematics,
    body_to_world_twist,
    desaturate,
    desaturate_speeds,
    mecanum_wheels,
    omni_wheels,
    world_to_body_twist,
)

# Standard mecanum chassis: wheelbase 0.4 m, track 0.3 m, wheel radius 0.1 m, so
# lx = 0.2, ly = 0.15, lx + ly = 0.35; order FL, FR, RL, RR.
MECANUM = WheelKinematics(mecanum_wheels(wheelbase=0.4, track=0.3, wheel_radius=0.1))
# Omni chassis with 3 wheels at 0°, 120°, 240°, 0.2 m from the centre, radius 0.05 m.
OMNI3 = WheelKinematics(omni_wheels([0.0, 2.0 * math.pi / 3, 4.0 * math.pi / 3], 0.2, 0.05))
# Omni chassis with 4 wheels at the corners (45°, 135°, 225°, 315°), 0.25 m, radius 0.05 m.
OMNI4 = WheelKinematics(
    omni_wheels([math.pi / 4, 3 * math.pi / 4, 5 * math.pi / 4, 7 * math.pi / 4], 0.25, 0.05)
)

speed = st.floats(min_value=-5.0, max_value=5.0)
twists = st.tuples(speed, speed, speed)


def test_when_mecanum_drives_forward_expect_all_wheels_forward():
    # FL = FR = RL = RR = vx / r = 1 / 0.1 = 10 rad/s
    assert MECANUM.inverse(Twist2D(1.0, 0.0, 0.0)) == pytest.approx([10.0, 10.0, 10.0, 10.0])


def test_when_mecanum_drives_left_expect_fl_rr_backwards_fr_rl_forwards():
    # FL = -vy / r, FR = +vy / r, RL = +vy / r, RR = -vy / r with vy = 1: -10, 10, 10, -10
    assert MECANUM.inverse(Twist2D(0.0, 1.0, 0.0)) == pytest.approx([-10.0, 10.0, 10.0, -10.0])


def test_when_mecanum_turns_left_expect_left_wheels_back_right_wheels_forward():
    # FL = RL = -(lx + ly) wz / r = -0.35 / 0.1 = -3.5; FR = RR = +3.5
    assert MECANUM.inverse(Twist2D(0.0, 0.0, 1.0)) == pytest.approx([-3.5, 3.5, -3.5, 3.5])


def test_when_mecanum_wheels_disagree_expect_least_squares_twist():
    # Wheel speeds (1, 2, 3, 4) fit no twist exactly; least squares gives the textbook
    # forward kinematics: vx = r/4 (FL + FR + RL + RR) = 0.1/4 * 10 = 0.25;
    # vy = r/4 (-FL + FR + RL - RR) = 0.1/4 * 0 = 0;
    # wz = r/(4 (lx + ly)) (-FL + FR - RL + RR) = 0.1/1.4 * 2 = 0.142857
    assert MECANUM.forward([1.0, 2.0, 3.0, 4.0]) == pytest.approx((0.25, 0.0, 0.1 / 1.4 * 2.0))


def test_when_mecanum_roller_signs_configured_expect_them_used():
    wheels = mecanum_wheels(0.4, 0.3, 0.1, roller_signs=(1, -1, -1, 1))
    # All rollers mirrored: FL row = [1, tan 45°, x tan 45° - y] / r = [1, 1, 0.2 - 0.15] / 0.1
    # so driving left turns FL forwards (+10) and turning gives only (lx - ly) / r = 0.5
    kinematics = WheelKinematics(wheels)
    assert kinematics.jacobian[0] == pytest.approx([10.0, 10.0, 0.5])


def test_when_mirrored_rollers_on_square_chassis_expect_config_error():
    # Mirrored rollers with lx = ly make the wz column zero: such a robot cannot turn.
    with pytest.raises(ConfigError, match='cannot produce'):
        WheelKinematics(mecanum_wheels(0.4, 0.4, 0.1, roller_signs=(1, -1, -1, 1)))


def test_when_three_omni_wheels_drive_forward_expect_tangential_components():
    # w_i = -sin(alpha_i) vx / r: 0, -sin 120° / 0.05 = -17.3205, -sin 240° / 0.05 = 17.3205
    s = math.sin(2.0 * math.pi / 3) / 0.05
    assert OMNI3.inverse(Twist2D(1.0, 0.0, 0.0)) == pytest.approx([0.0, -s, s], abs=1e-12)


def test_when_three_omni_wheels_turn_expect_all_equal():
    # w_i = R wz / r = 0.2 / 0.05 = 4 rad/s for every wheel
    assert OMNI3.inverse(Twist2D(0.0, 0.0, 1.0)) == pytest.approx([4.0, 4.0, 4.0])


def test_when_three_omni_wheel_speeds_given_expect_twist():
    s = math.sin(2.0 * math.pi / 3) / 0.05
    # the speeds of vx = 1 (see above) give back vx = 1
    assert OMNI3.forward([0.0, -s, s]) == pytest.approx((1.0, 0.0, 0.0), abs=1e-12)


def test_when_four_omni_wheels_drive_left_expect_cosine_components():
    # w_i = cos(alpha_i) vy / r = ±cos 45° / 0.05 = ±14.1421: +, -, -, +
    c = math.cos(math.pi / 4) / 0.05
    assert OMNI4.inverse(Twist2D(0.0, 1.0, 0.0)) == pytest.approx([c, -c, -c, c])


def test_when_four_omni_wheels_drive_forward_expect_sine_components():
    # w_i = -sin(alpha_i) vx / r = -14.1421, -14.1421, +14.1421, +14.1421
    s = math.sin(math.pi / 4) / 0.05
    assert OMNI4.inverse(Twist2D(1.0, 0.0, 0.0)) == pytest.approx([-s, -s, s, s])


def test_when_two_wheels_expect_config_error():
    with pytest.raises(ConfigError, match='>= 3 wheels'):
        WheelKinematics(omni_wheels([0.0, math.pi], 0.2, 0.05))


def test_when_omni_wheels_all_roll_same_way_expect_config_error():
    # Three wheels rolling along x at different places: vy is unreachable.
    wheels = [Wheel(0.0, y, 0.05) for y in (-0.2, 0.0, 0.2)]
    with pytest.raises(ConfigError, match='cannot produce'):
        WheelKinematics(wheels)


def test_when_wheel_built_from_numpy_floats_expect_accepted():
    assert Wheel(np.float32(0.5), 0.0, np.float32(0.25)).x == 0.5


def test_when_wheel_radius_zero_expect_config_error():
    with pytest.raises(ConfigError, match='radius'):
        Wheel(0.0, 0.0, 0.0)


def test_when_roller_across_rim_expect_config_error():
    with pytest.raises(ConfigError, match='roller_angle'):
        Wheel(0.0, 0.0, 0.05, roller_angle=0.5 * math.pi)


def test_when_roller_signs_wrong_expect_config_error():
    with pytest.raises(ConfigError, match='roller_signs'):
        mecanum_wheels(0.4, 0.3, 0.1, roller_signs=(1, 1, 1))


def test_when_twist_nan_expect_rejected():
    with pytest.raises(InputRejectedError, match='finite'):
        MECANUM.inverse((math.nan, 0.0, 0.0))


def test_when_wheel_count_wrong_expect_rejected():
    with pytest.raises(InputRejectedError, match='expected 4'):
        MECANUM.forward([1.0, 2.0, 3.0])


def test_when_jacobian_read_expect_read_only():
    with pytest.raises(ValueError, match='read-only'):
        MECANUM.jacobian[0, 0] = 1.0


def test_when_one_wheel_over_limit_expect_all_scaled_alike():
    # max |w| / limit = 20 / 10 = 2, so every wheel is halved
    assert desaturate([10.0, -20.0, 5.0, 0.0], 10.0) == pytest.approx([5.0, -10.0, 2.5, 0.0])


def test_when_all_wheels_within_limit_expect_unchanged():
    assert desaturate([1.0, -2.0, 3.0], 10.0) == pytest.approx([1.0, -2.0, 3.0])


def test_when_limits_per_wheel_expect_worst_ratio_used():
    # ratios 8/10 = 0.8 and 6/4 = 1.5: scale by 1 / 1.5
    assert desaturate([8.0, 6.0], [10.0, 4.0]) == pytest.approx([8.0 / 1.5, 4.0])


def test_when_desaturated_expect_input_not_modified():
    speeds = np.array([20.0, 0.0])
    desaturate(speeds, 10.0)
    assert speeds[0] == 20.0


@pytest.mark.parametrize(
    ('speeds', 'limit'), [([math.nan], 1.0), ([1.0], 0.0), ([1.0, 2.0], [1.0])]
)
def test_when_desaturate_input_invalid_expect_rejected(speeds, limit):
    with pytest.raises(InputRejectedError):
        desaturate(speeds, limit)


def test_when_mecanum_command_desaturated_expect_direction_of_motion_kept():
    # (vx, vy, wz) = (2, 1, 1): FL = (2 - 1 - 0.35) / 0.1 = 6.5, FR = (2 + 1 + 0.35) / 0.1
    # = 33.5, RL = (2 + 1 - 0.35) / 0.1 = 26.5, RR = (2 - 1 + 0.35) / 0.1 = 13.5.
    # Limit 20: scale 20 / 33.5, so the twist becomes (2, 1, 1) * 20 / 33.5.
    speeds = desaturate(MECANUM.inverse((2.0, 1.0, 1.0)), 20.0)
    scale = 20.0 / 33.5
    assert MECANUM.forward(speeds) == pytest.approx((2.0 * scale, scale, scale))


def test_when_speeds_desaturated_as_floats_expect_scaled_and_factor():
    # max |w| / limit = 20 / 10 = 2: every wheel halved, factor 1 / 2
    speeds, factor = desaturate_speeds([10.0, -20.0, 5.0, 0.0], 10.0)
    assert speeds == pytest.approx((5.0, -10.0, 2.5, 0.0))
    assert factor == pytest.approx(0.5)


def test_when_speeds_within_limit_as_floats_expect_unchanged_and_factor_one():
    assert desaturate_speeds((1.0, -2.0, 3.0), 10.0) == ((1.0, -2.0, 3.0), 1.0)


@pytest.mark.parametrize(('speeds', 'limit'), [([math.nan], 1.0), ([1.0], 0.0), ([1.0], math.nan)])
def test_when_desaturate_speeds_input_invalid_expect_rejected(speeds, limit):
    with pytest.raises(InputRejectedError):
        desaturate_speeds(speeds, limit)


def test_when_wheel_speeds_of_nan_twist_expect_rejected():
    with pytest.raises(InputRejectedError, match='finite'):
        MECANUM.wheel_speeds((0.0, math.inf, 0.0))


def test_when_forward_given_a_matrix_expect_rejected():
    with pytest.raises(InputRejectedError, match='expected 4'):
        MECANUM.forward([[1.0, 2.0], [3.0, 4.0]])


@given(twists)
def test_when_wheel_speeds_as_floats_expect_same_as_inverse(twist):
    assert MECANUM.wheel_speeds(twist) == pytest.approx(MECANUM.inverse(twist), rel=1e-12)


@given(twists, st.floats(min_value=0.1, max_value=100.0))
def test_when_desaturated_as_floats_expect_same_as_desaturate(twist, limit):
    speeds = MECANUM.inverse(twist)
    limited, factor = desaturate_speeds(speeds.tolist(), limit)
    assert limited == pytest.approx(desaturate(speeds, limit), rel=1e-12)
    peak = float(np.max(np.abs(speeds)))
    assert factor == pytest.approx(min(1.0, limit / peak) if peak else 1.0, rel=1e-12)


def test_when_body_twist_rotated_to_world_expect_forward_becomes_left():
    # Body heading +90°: its forward (x) is the world's y; wz is unchanged
    assert body_to_world_twist((1.0, 0.0, 0.5), 0.5 * math.pi) == pytest.approx((0.0, 1.0, 0.5))


def test_when_world_twist_rotated_to_body_expect_left_becomes_forward():
    # Inverse of the case above: world +y is the body's forward when it heads +90°
    assert world_to_body_twist((0.0, 1.0, 0.5), 0.5 * math.pi) == pytest.approx((1.0, 0.0, 0.5))


def test_when_twist_wrong_size_expect_rejected():
    with pytest.raises(InputRejectedError, match='3 finite values'):
        body_to_world_twist((1.0, 0.0), 0.0)


@given(twists)
def test_when_mecanum_forward_of_inverse_expect_same_twist(twist):
    assert MECANUM.forward(MECANUM.inverse(twist)) == pytest.approx(twist, abs=1e-9)


@given(twists)
def test_when_three_omni_forward_of_inverse_expect_same_twist(twist):
    assert OMNI3.forward(OMNI3.inverse(twist)) == pytest.approx(twist, abs=1e-9)


@given(twists)
def test_when_four_omni_forward_of_inverse_expect_same_twist(twist):
    assert OMNI4.forward(OMNI4.inverse(twist)) == pytest.approx(twist, abs=1e-9)


@given(twists, st.floats(min_value=0.1, max_value=100.0))
def test_when_any_twist_desaturated_expect_within_limit_and_parallel(twist, limit):
    speeds = desaturate(MECANUM.inverse(twist), limit)
    assert np.max(np.abs(speeds)) <= limit * (1.0 + 1e-12)
    result = np.array(MECANUM.forward(speeds))
    # result = s * twist with one s in (0, 1] for all three components
    norm = np.linalg.norm(twist)
    if norm > 1e-9:
        scale = float(result @ np.array(twist)) / norm**2
        assert 0.0 < scale <= 1.0 + 1e-9
        assert result == pytest.approx(scale * np.array(twist), abs=1e-9)


@given(twists, st.floats(min_value=-10.0, max_value=10.0))
def test_when_twist_rotated_there_and_back_expect_same_twist(twist, yaw):
    assert world_to_body_twist(body_to_world_twist(twist, yaw), yaw) == pytest.approx(
        twist, abs=1e-9
    )
