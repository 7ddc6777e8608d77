"""The simulated spinning robot: where its plates are, and which projectiles hit them."""

import math

import pytest
from rm_base.geometry.ballistics import ProjectileModel, solve_ballistic
from rm_base.sim import SimConfigError
from rm_base.sim.target import target_from_config

SPEED = 15.0
DRAG_FREE = ProjectileModel(drag=0.0)


def aim_pitch(distance, height):
    return solve_ballistic(distance, height, SPEED, DRAG_FREE).pitch


def test_a_shot_solved_for_a_still_plate_hits_it_and_one_a_plate_width_off_misses():
    target = target_from_config({'x': 4.0, 'v_yaw': 0.0, 'z': 0.3, 'pivot_height': 0.4,
                                 'barrel_length': 0.0})
    pitch = aim_pitch(3.75, 0.3 - 0.4)  # plate 0 faces the shooter at x = 4 - 0.25
    assert target.shoot(0, (0.0, 0.0), 0.0, pitch, SPEED) == 0
    off = 0.135 / 3.75  # a plate's width to the side
    assert target.shoot(0, (0.0, 0.0), off, pitch, SPEED) is None
    assert target.shoot(0, (0.0, 0.0), 0.0, pitch - 0.05, SPEED) is None  # over it
    assert (target.shots, dict(target.hits)) == (3, {0: 1})


def test_a_plate_seen_edge_on_deflects_and_the_back_plates_are_never_hit():
    # plate 0 turned away
    edge = target_from_config({'x': 4.0, 'v_yaw': 0.0, 'yaw': 1.4, 'barrel_length': 0.0})
    pitch = aim_pitch(math.hypot(4.0 - 0.25 * math.cos(1.4), 0.25 * math.sin(1.4)), -0.1)
    yaw = math.atan2(-0.25 * math.sin(1.4), 4.0 - 0.25 * math.cos(1.4))
    assert edge.shoot(0, (0.0, 0.0), yaw, pitch, SPEED) is None


def test_the_spin_during_the_flight_counts():
    # plate 0 faces the shooter at t = flight time, not at the shot
    flight = 3.75 / (SPEED * math.cos(-aim_pitch(3.75, -0.1)))
    spinning = target_from_config({'x': 4.0, 'v_yaw': 2.0, 'yaw': -2.0 * flight,
                                   'pivot_height': 0.4, 'barrel_length': 0.0})
    assert spinning.shoot(0, (0.0, 0.0), 0.0, aim_pitch(3.75, -0.1), SPEED) == 0
    late = target_from_config({'x': 4.0, 'v_yaw': 2.0, 'yaw': 0.0, 'pivot_height': 0.4,
                               'barrel_length': 0.0})  # aimed where it was
    assert late.shoot(0, (0.0, 0.0), 0.0, aim_pitch(3.75, -0.1), SPEED) is None


def test_the_truth_is_what_a_perfect_tracker_reports():
    target = target_from_config({'x': 4.0, 'vx': 0.5, 'v_yaw': 2.0, 'yaw': 0.1})
    truth = target.truth(1_000_000_000)
    assert truth.center == pytest.approx((4.5, 0.0))
    assert truth.yaw == pytest.approx(2.1)
    assert target.plates(1_000_000_000)[0].position[0] == pytest.approx(
        4.5 - 0.25 * math.cos(2.1))


def test_a_bad_key_is_refused():
    with pytest.raises(SimConfigError, match='armors'):
        target_from_config({'armors': 5})
