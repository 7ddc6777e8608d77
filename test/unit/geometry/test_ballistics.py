import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry import (
    STANDARD_GRAVITY,
    ProjectileModel,
    rotation_matrix_from_rpy,
    solve_ballistic,
    trajectory_height,
)

VACUUM = ProjectileModel(drag=0.0, gravity=9.8)  # g = 9.8 keeps the hand arithmetic short
DRAG_17MM = ProjectileModel(drag=0.02, gravity=9.8)


def integrate_in_time(elevation, speed, drag, gravity, distance, dt=1e-4):
    """Independent reference: RK4 in time of a = -k |v| v - g z, stopped at x = distance.

    Returns (height [m], time [s]) at the crossing, interpolated linearly within the step.
    """
    x = y = t = 0.0
    vx, vy = speed * math.cos(elevation), speed * math.sin(elevation)

    def acceleration(vx, vy):
        speed_now = math.hypot(vx, vy)
        return -drag * speed_now * vx, -drag * speed_now * vy - gravity

    while True:
        a1 = acceleration(vx, vy)
        a2 = acceleration(vx + 0.5 * dt * a1[0], vy + 0.5 * dt * a1[1])
        a3 = acceleration(vx + 0.5 * dt * a2[0], vy + 0.5 * dt * a2[1])
        a4 = acceleration(vx + dt * a3[0], vy + dt * a3[1])
        # Position from the RK4 stages of the velocity (exact for this pairing).
        nx = x + dt * (vx + dt * (a1[0] + a2[0] + a3[0]) / 6.0)
        ny = y + dt * (vy + dt * (a1[1] + a2[1] + a3[1]) / 6.0)
        vx += dt * (a1[0] + 2.0 * a2[0] + 2.0 * a3[0] + a4[0]) / 6.0
        vy += dt * (a1[1] + 2.0 * a2[1] + 2.0 * a3[1] + a4[1]) / 6.0
        if nx >= distance:
            fraction = (distance - x) / (nx - x)
            return y + fraction * (ny - y), t + fraction * dt
        x, y, t = nx, ny, t + dt


def test_when_no_drag_and_level_target_expect_closed_form_lower_angle():
    # v = 20, g = 9.8, d = 10, h = 0: sin(2 theta) = g d / v² = 98 / 400 = 0.245,
    # theta = asin(0.245) / 2 = 0.247520 / 2 = 0.123760 rad (7.09°), the flat shot (the
    # lob is pi/2 - theta = 1.447). Aiming up is negative pitch: pitch = -0.123760.
    # Time of flight d / (v cos theta) = 10 / (20 * 0.992352) = 0.503854 s.
    solution = solve_ballistic(10.0, 0.0, 20.0, VACUUM)
    assert solution.pitch == pytest.approx(-0.5 * math.asin(0.245), rel=1e-12)
    assert solution.time_of_flight_s == pytest.approx(0.503854, rel=1e-6)


def test_when_no_drag_and_target_above_expect_formula_value_and_negative_pitch():
    # d = 10, h = 2, v = 20, g = 9.8:
    # D = v⁴ - g (g d² + 2 h v²) = 160000 - 9.8 (980 + 1600) = 160000 - 25284 = 134716
    # tan theta = (v² - sqrt(D)) / (g d) = (400 - 367.036783) / 98 = 0.336359
    # theta = atan(0.336359) = 0.324471 rad, above the line of sight atan(0.2) = 0.197396
    solution = solve_ballistic(10.0, 2.0, 20.0, VACUUM)
    assert solution.elevation == pytest.approx(0.324471, rel=1e-5)
    assert solution.pitch == pytest.approx(-0.324471, rel=1e-5)


def test_when_no_drag_and_target_below_expect_positive_pitch_barrel_down():
    # d = 10, h = -2: D = 160000 - 9.8 (980 - 1600) = 166076, sqrt(D) = 407.524232
    # tan theta = (400 - 407.524232) / 98 = -0.076778, theta = -0.076628: barrel down,
    # so the REP 103 pitch is positive, 0.076628.
    solution = solve_ballistic(10.0, -2.0, 20.0, VACUUM)
    assert solution.pitch == pytest.approx(0.076628, rel=1e-4)


def test_when_target_above_expect_rep103_barrel_direction_points_up():
    solution = solve_ballistic(10.0, 2.0, 20.0, VACUUM)
    # The barrel is the x axis of a frame pitched by the solution: R_y(pitch) @ x.
    barrel = rotation_matrix_from_rpy(0.0, solution.pitch, 0.0) @ np.array([1.0, 0.0, 0.0])
    assert barrel[2] > 0.0  # up, although the pitch is negative
    assert math.atan2(barrel[2], barrel[0]) == pytest.approx(solution.elevation)


def test_when_target_very_close_expect_no_cancellation():
    # d = 1 mm, h = 0, v = 20: tan theta = g d / (v² + sqrt(D)) with D ≈ v⁴, so
    # theta ≈ g d / (2 v²) = 9.8e-3 / 800 = 1.225e-5 rad. The textbook form
    # (v² - sqrt(D)) / (g d) would lose about ten digits to cancellation here.
    solution = solve_ballistic(1e-3, 0.0, 20.0, VACUUM)
    assert solution.elevation == pytest.approx(1.225e-5, rel=1e-9)


def test_when_beyond_vacuum_range_expect_none():
    # Largest level range v² / g = 100 / 9.8 = 10.204 m.
    assert solve_ballistic(10.3, 0.0, 10.0, VACUUM) is None
    assert solve_ballistic(10.2, 0.0, 10.0, VACUUM) is not None


def test_when_target_above_highest_reach_expect_none():
    # Straight up a 10 m/s bullet rises v² / (2 g) = 100 / 19.6 = 5.1 m; nearer the
    # horizon it reaches less: at d = 1 m the highest point is
    # v² / (2 g) - g d² / (2 v²) = 5.102 - 0.049 = 5.053 m.
    assert solve_ballistic(1.0, 5.1, 10.0, VACUUM) is None
    assert solve_ballistic(1.0, 5.0, 10.0, VACUUM) is not None


def test_when_target_straight_above_expect_none():
    assert solve_ballistic(0.0, 1.0, 20.0, VACUUM) is None


@pytest.mark.parametrize(
    ('distance', 'height', 'speed', 'message'),
    [
        (10.0, 0.0, 0.0, 'speed'),
        (10.0, 0.0, -5.0, 'speed'),
        (-1.0, 0.0, 20.0, 'distance'),
        (math.nan, 0.0, 20.0, 'finite'),
        (10.0, math.inf, 20.0, 'finite'),
        (10.0, 0.0, math.nan, 'finite'),
    ],
)
def test_when_input_invalid_expect_rejected(distance, height, speed, message):
    with pytest.raises(InputRejectedError, match=message):
        solve_ballistic(distance, height, speed, DRAG_17MM)


@pytest.mark.parametrize(
    ('distance', 'height', 'speed', 'drag'),
    [
        (8.0, 0.5, 25.0, 0.02),  # 17 mm at an infantry
        (5.0, 1.2, 15.8, 0.009),  # 42 mm, hero
        (20.0, 3.0, 28.0, 0.038),  # long shot, up a slope, heavy drag
        (3.0, -1.5, 12.0, 0.02),  # down from a height
        (2.0, 3.0, 16.0, 0.02),  # steep: elevation about 65°
    ],
)
def test_when_drag_expect_solution_hits_in_independent_time_integration(
    distance, height, speed, drag
):
    model = ProjectileModel(drag=drag, gravity=9.8)
    solution = solve_ballistic(distance, height, speed, model)
    reached, time_s = integrate_in_time(solution.elevation, speed, drag, 9.8, distance)
    assert reached == pytest.approx(height, abs=2e-4)  # m
    assert solution.time_of_flight_s == pytest.approx(time_s, abs=1e-5)


def test_when_drag_expect_higher_aim_and_longer_flight_than_vacuum():
    vacuum = solve_ballistic(8.0, 0.5, 25.0, VACUUM)
    dragged = solve_ballistic(8.0, 0.5, 25.0, DRAG_17MM)
    # Drag slows the bullet, so it needs longer and must be aimed higher (more negative).
    assert dragged.pitch < vacuum.pitch
    assert dragged.time_of_flight_s > vacuum.time_of_flight_s


def test_when_drag_vanishes_expect_vacuum_solution():
    almost = solve_ballistic(10.0, 2.0, 20.0, ProjectileModel(drag=1e-12, gravity=9.8))
    exact = solve_ballistic(10.0, 2.0, 20.0, VACUUM)
    assert almost.pitch == pytest.approx(exact.pitch, abs=1e-9)
    assert almost.time_of_flight_s == pytest.approx(exact.time_of_flight_s, abs=1e-9)


def test_when_drag_expect_flat_shot_not_lob():
    solution = solve_ballistic(8.0, 0.5, 25.0, DRAG_17MM)
    # The flat shot is on the rising side of height-versus-elevation: aiming a little
    # higher would hit higher (past the peak, on the lob side, it would hit lower).
    higher, _ = trajectory_height(8.0, solution.pitch - 0.01, 25.0, DRAG_17MM)
    assert higher > 0.5


def test_when_drag_and_within_vacuum_range_but_not_drag_range_expect_none():
    # A drag-free height at the target is y = s d - c (1 + s²), s = tan(elevation),
    # c = g d² / (2 v²), highest d² / (4 c) - c at s = d / (2 c). v = 16, d = 20:
    # c = 9.8 * 400 / 512 = 7.656 m, highest 400 / 30.625 - 7.656 = 5.41 m: reachable.
    # With drag 1 / vx² grows at least as exp(2 k x), so the bullet is never higher than
    # the same parabola with d² / 2 replaced by E = (exp(2 k d) - 1 - 2 k d) / (4 k²);
    # k = 0.04: 2 k d = 1.6, E = (4.953 - 1 - 1.6) / 0.0064 = 367.6 m² (not 200),
    # c = 9.8 * 367.6 / 256 = 14.07 m, highest 400 / 56.28 - 14.07 = -6.96 m: out of range.
    assert solve_ballistic(20.0, 0.0, 16.0, ProjectileModel(drag=0.0, gravity=9.8)) is not None
    assert solve_ballistic(20.0, 0.0, 16.0, ProjectileModel(drag=0.04, gravity=9.8)) is None


def test_when_no_drag_forward_model_expect_parabola():
    # pitch -0.3 (up): tan(0.3) = 0.309336, 1 / cos² = 1.095689;
    # y = d tan - g d² / (2 v² cos²) = 10 * 0.309336 - 9.8 * 100 * 1.095689 / 800
    #   = 3.093362 - 1.342219 = 1.751144 m; t = 10 / (20 cos 0.3) = 0.523376 s
    height, time_s = trajectory_height(10.0, -0.3, 20.0, VACUUM)
    assert height == pytest.approx(1.751144, rel=1e-6)
    assert time_s == pytest.approx(0.523376, rel=1e-6)


@pytest.mark.parametrize('pitch', [math.pi / 2, -math.pi / 2, math.nan])
def test_when_forward_model_pitch_vertical_expect_rejected(pitch):
    with pytest.raises(InputRejectedError, match='pitch'):
        trajectory_height(5.0, pitch, 20.0, VACUUM)


def test_when_shot_spent_before_distance_expect_forward_model_none():
    # A steep, heavily dragged shot: its horizontal speed is gone long before 200 m.
    assert trajectory_height(200.0, -1.2, 10.0, ProjectileModel(drag=0.05)) is None


@pytest.mark.parametrize(
    ('kwargs', 'message'),
    [
        ({'drag': -0.01}, 'drag'),
        ({'drag': math.nan}, 'drag'),
        ({'gravity': 0.0}, 'gravity'),
        ({'gravity': math.inf}, 'gravity'),
        ({'drag': True}, 'drag'),
    ],
)
def test_when_model_invalid_expect_config_error(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        ProjectileModel(**kwargs)


def test_default_gravity_is_standard():
    assert ProjectileModel().gravity == STANDARD_GRAVITY == 9.80665


@given(
    st.floats(min_value=0.2, max_value=25.0),
    st.floats(min_value=-3.0, max_value=5.0),
    st.floats(min_value=8.0, max_value=32.0),
    st.sampled_from([0.0, 0.005, 0.02, 0.04]),
)
def test_invariant_solution_reaches_target_in_forward_model(distance, height, speed, drag):
    model = ProjectileModel(drag=drag)
    solution = solve_ballistic(distance, height, speed, model)
    assume(solution is not None)
    reached, time_s = trajectory_height(distance, solution.pitch, speed, model)
    assert reached == pytest.approx(height, abs=1e-6)
    assert time_s == pytest.approx(solution.time_of_flight_s, rel=1e-9)
    # Always above the line of sight: a bullet falls below its launch line.
    assert solution.elevation > math.atan2(height, distance)


@given(
    st.floats(min_value=0.2, max_value=25.0),
    st.floats(min_value=-3.0, max_value=5.0),
    st.floats(min_value=8.0, max_value=32.0),
)
def test_invariant_drag_never_reaches_what_vacuum_cannot(distance, height, speed):
    if solve_ballistic(distance, height, speed, ProjectileModel()) is None:
        assert solve_ballistic(distance, height, speed, ProjectileModel(drag=0.02)) is None
