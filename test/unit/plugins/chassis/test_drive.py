"""SwerveDrive: steering targets kept between ticks, wheels read along the measured angles."""

import math

import pytest
from rm_base.errors import InputRejectedError
from rm_base.geometry import SwerveKinematics, square_modules
from rm_plugins.chassis.drive import SwerveDrive

R = 0.05  # wheel radius [m]
LX, LY = 0.2, 0.15  # half wheelbase, half track [m]


def drive():
    return SwerveDrive(SwerveKinematics(square_modules(2 * LX, 2 * LY, R)))


def test_nothing_is_planned_or_read_before_the_angles_are_observed():
    d = drive()
    with pytest.raises(InputRejectedError, match='not been observed'):
        d.wheel_speeds((1.0, 0.0, 0.0))
    with pytest.raises(InputRejectedError, match='not been observed'):
        d.forward((0.0,) * 4)
    with pytest.raises(InputRejectedError, match='not been observed'):
        d.steer_targets  # noqa: B018 (the property raises)


@pytest.mark.parametrize('angles', [(0.0, 0.0, 0.0), (0.0, 0.0, math.nan, 0.0)])
def test_a_wrong_number_of_angles_or_a_nan_is_rejected(angles):
    with pytest.raises(InputRejectedError, match='4 finite steering angles'):
        drive().observe(angles)


def test_straight_ahead_with_the_modules_along_x():
    d = drive()
    d.observe((0.0,) * 4)
    assert d.wheel_speeds((1.0, 0.0, 0.0)) == pytest.approx((1.0 / R,) * 4)
    assert d.steer_targets == pytest.approx((0.0,) * 4)
    assert d.forward((1.0 / R,) * 4) == pytest.approx((1.0, 0.0, 0.0))


def test_a_module_pointing_backwards_reverses_its_wheel_instead_of_turning_round():
    d = drive()
    back = math.radians(170.0)
    d.observe((0.0, 0.0, back, 0.0))
    speeds = d.wheel_speeds((1.0, 0.0, 0.0))
    # turned 10 degrees to 180, not 170 degrees to 0; slowed by cos(10 deg) while it turns
    assert d.steer_targets[2] == pytest.approx(math.pi)
    assert speeds[2] == pytest.approx(-math.cos(math.radians(10.0)) / R)
    assert speeds[0] == pytest.approx(1.0 / R)


def test_targets_carry_over_between_ticks_and_restart_from_the_modules_after_reset():
    d = drive()
    d.observe((0.0,) * 4)
    d.wheel_speeds((0.0, 1.0, 0.0))  # sideways: every module asked to 90 degrees
    assert d.steer_targets == pytest.approx((math.pi / 2,) * 4)
    d.observe((0.3,) * 4)  # still turning
    d.wheel_speeds((0.0, 0.0, 0.0))  # stop: the modules keep their targets
    assert d.steer_targets == pytest.approx((math.pi / 2,) * 4)
    d.reset()
    d.observe((0.3,) * 4)
    assert d.steer_targets == pytest.approx((0.3,) * 4)


def test_the_odometry_reads_the_wheels_along_the_measured_angles():
    d = drive()
    d.observe((math.pi / 2,) * 4)
    vx, vy, wz = d.forward((2.0 / R,) * 4)
    assert (vx, vy, wz) == pytest.approx((0.0, 2.0, 0.0), abs=1e-12)
