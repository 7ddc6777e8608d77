"""The auto-aim point: the facing plate ahead of time, the centre when it spins too fast."""

import math

import pytest
from rm_base.geometry.armor_target import ArmorTarget
from rm_base.geometry.ballistics import ProjectileModel
from rm_plugins.autoaim.solver import AimSettings, aim_point

STILL = ArmorTarget(center=(4.0, 0.0), z=0.3, velocity=(0.0, 0.0, 0.0), yaw=0.0, v_yaw=0.0,
                    radius_1=0.25, radius_2=0.25, dz=0.0, armors_num=4)
SETTINGS = AimSettings(latency_s=0.05, model=ProjectileModel(drag=0.0))
ORIGIN = (0.0, 0.0, 0.35)


def test_a_still_target_is_aimed_at_its_facing_plate_with_the_flight_time():
    found = aim_point(STILL, 0.01, ORIGIN, 15.0, SETTINGS)
    assert found.plate == 0 and found.point == pytest.approx((3.75, 0.0, 0.3))
    assert found.flight_s == pytest.approx(3.75 / 15.0, rel=0.01)
    assert found.distance == pytest.approx(3.75)


def test_a_spinning_target_is_aimed_where_the_plate_will_be_after_age_latency_and_flight():
    spinning = ArmorTarget(**{**STILL.__dict__, 'v_yaw': 2.0})
    found = aim_point(spinning, 0.01, ORIGIN, 15.0, SETTINGS)
    ahead = 0.01 + 0.05 + found.flight_s
    psi = 2.0 * ahead + found.plate * math.pi / 2
    # within 5 mm: the point is predicted with the flight solved one step before
    assert found.point[1] == pytest.approx(-0.25 * math.sin(psi), abs=5e-3)
    assert found.plate == 3  # plate 0 (yaw 0.62) leaving, plate 3 (-0.95) coming: the lead


def test_too_fast_a_spin_is_aimed_at_the_centre_and_out_of_range_is_none():
    fast = ArmorTarget(**{**STILL.__dict__, 'v_yaw': -8.0})
    found = aim_point(fast, 0.0, ORIGIN, 15.0, SETTINGS)
    assert found.plate is None and found.point == pytest.approx((4.0, 0.0, 0.3))
    far = ArmorTarget(**{**STILL.__dict__, 'center': (60.0, 0.0)})
    assert aim_point(far, 0.0, ORIGIN, 15.0, SETTINGS) is None
