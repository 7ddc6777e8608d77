"""A spinning robot's armours ahead of time, and the one to aim at (docs/AUTO_AIM.md)."""

import math

import pytest
from rm_base.errors import InputRejectedError
from rm_base.geometry.armor_target import ArmorTarget, armors, center_point, facing_armor

# the fact sheet's worked example: t = 0.1 s
EXAMPLE = ArmorTarget(center=(3.0, 0.5), z=0.1, velocity=(0.5, 0.0, 0.0), yaw=0.2, v_yaw=6.0,
                      radius_1=0.25, radius_2=0.20, dz=0.05, armors_num=4)
LEAD = math.radians(15.0)


def test_the_worked_examples_armours_land_where_the_tracker_draws_them():
    plates = armors(EXAMPLE, 0.1)
    assert plates[0].position == pytest.approx((2.8758, 0.3207, 0.100), abs=1e-4)
    assert plates[0].yaw == pytest.approx(0.80)
    assert plates[3].position == pytest.approx((2.9065, 0.6393, 0.150), abs=1e-4)
    assert plates[3].yaw == pytest.approx(5.512 - 2 * math.pi, abs=1e-3)  # wrapped
    assert [p.index for p in plates] == [0, 1, 2, 3]
    assert plates[1].position[2] == pytest.approx(0.15)  # the other pair: z + dz, r2


def test_the_incoming_plate_is_chosen_as_the_leading_solver_chooses_it():
    assert facing_armor(EXAMPLE, 0.1, (0.0, 0.0), LEAD).index == 3  # FYT's choice
    assert facing_armor(EXAMPLE, 0.1, (0.0, 0.0), 0.0).index == 0  # nearest, no lead


def test_angles_are_compared_wrapped_behind_the_shooter():
    # the centre behind the shooter (bearing +3.138): the facing plate's yaw is -3.1, which
    # an unwrapped comparison would think a full turn away
    behind = ArmorTarget(center=(-3.0, 0.01), z=0.1, velocity=(0.0, 0.0, 0.0),
                         yaw=-3.1, v_yaw=0.0, radius_1=0.25, radius_2=0.25, dz=0.0,
                         armors_num=4)
    chosen = facing_armor(behind, 0.0, (0.0, 0.0), LEAD)
    assert chosen.index == 0
    assert chosen.position[0] == pytest.approx(-2.75, abs=1e-3)  # the near side
    # the same target in an unwrapped comparison: plate 2 (yaw ~0.04) looks "nearest"
    alpha = math.atan2(0.01, -3.0)  # +3.138
    unwrapped = min(armors(behind, 0.0), key=lambda a: abs(a.yaw - alpha))
    assert unwrapped.index != chosen.index


def test_two_and_three_plate_robots_have_one_radius_and_one_height():
    outpost = ArmorTarget(center=(5.0, 0.0), z=1.0, velocity=(0.0, 0.0, 0.0), yaw=0.0,
                          v_yaw=0.8, radius_1=0.55, radius_2=0.3, dz=0.2, armors_num=3)
    plates = armors(outpost, 0.0)
    assert len(plates) == 3
    assert {round(p.position[2], 6) for p in plates} == {1.0}
    assert all(math.hypot(p.position[0] - 5.0, p.position[1]) == pytest.approx(0.55)
               for p in plates)
    assert center_point(outpost, 1.0) == (5.0, 0.0, 1.0)
    assert center_point(EXAMPLE, 0.0) == pytest.approx((3.0, 0.5, 0.125))


@pytest.mark.parametrize('change', [
    {'yaw': math.nan}, {'armors_num': 5}, {'radius_1': 0.0}, {'velocity': (math.inf, 0, 0)},
])
def test_a_target_with_a_bad_value_is_refused(change):
    fields = {**EXAMPLE.__dict__, **change}
    with pytest.raises(InputRejectedError):
        ArmorTarget(**fields)
