"""Swerve kinematics: module states within 90° of where they point, and the twist back."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry.swerve import (
    ModuleState,
    SwerveKinematics,
    SwerveModule,
    nearest_module_state,
    square_modules,
)

R = 0.06  # [m] wheel radius
SQUARE = SwerveKinematics(square_modules(0.4, 0.4, R))  # modules at (±0.2, ±0.2)
AHEAD = (0.0, 0.0, 0.0, 0.0)
PI = math.pi


def flat(states):
    return [v for state in states for v in state]


@pytest.mark.parametrize(('direction', 'current', 'want'), [
    (0.0, 0.0, ModuleState(0.0, 10.0)),
    (PI / 2, 0.0, ModuleState(PI / 2, 10.0)),  # exactly 90°: turn, do not flip
    (PI / 2 + 0.1, 0.0, ModuleState(-PI / 2 + 0.1, -10.0)),  # past 90°: flip, drive back
    (PI, 0.0, ModuleState(0.0, -10.0)),  # straight back: no turn at all
    (-3 * PI / 4, 0.0, ModuleState(PI / 4, -10.0)),
    (0.1, 4 * PI, ModuleState(4 * PI + 0.1, 10.0)),  # the joint's count of turns is kept
    (PI - 0.1, -2 * PI, ModuleState(-2 * PI - 0.1, -10.0)),
])
def test_a_module_turns_at_most_90_degrees_and_flips_its_drive_instead(direction, current, want):
    got = nearest_module_state(direction, 10.0, current)
    assert got == pytest.approx(want)


def test_a_module_that_should_not_move_stays_where_it_points():
    assert nearest_module_state(1.0, 0.0, 0.3) == (0.3, 0.0)


def test_driving_sideways_points_every_module_left():
    states = SQUARE.module_states((0.0, 1.2, 0.0), AHEAD)
    assert flat(states) == pytest.approx([PI / 2, 1.2 / R] * 4)


def test_driving_backwards_drives_back_rather_than_turning_round():
    states = SQUARE.module_states((-1.2, 0.0, 0.0), AHEAD)
    assert flat(states) == pytest.approx([0.0, -1.2 / R] * 4)


def test_turning_on_the_spot_points_every_module_along_the_circle():
    wz = 3.0
    states = SQUARE.module_states((0.0, 0.0, wz), AHEAD)
    rim = wz * math.hypot(0.2, 0.2) / R
    # FL at (0.2, 0.2) moves at 135°: within 90° of 0 that is -45° driven backwards
    assert flat(states) == pytest.approx(
        [-PI / 4, -rim, PI / 4, rim, PI / 4, -rim, -PI / 4, rim]
    )


def test_a_module_still_turning_is_slowed_by_the_cosine_of_its_error():
    states = SQUARE.module_states((0.0, 1.2, 0.0), AHEAD, measured=(PI / 3,) * 4)
    assert states[0] == pytest.approx((PI / 2, 1.2 / R * math.cos(PI / 6)))
    states = SQUARE.module_states((0.0, 1.2, 0.0), AHEAD, measured=(-PI / 2,) * 4)
    assert states[0].speed == 0.0  # pointing the wrong way: it waits


@given(
    vx=st.floats(-3.0, 3.0), vy=st.floats(-3.0, 3.0), wz=st.floats(-8.0, 8.0),
    current=st.lists(st.floats(-10.0, 10.0), min_size=4, max_size=4),
)
def test_forward_gives_back_the_twist_the_modules_were_set_for(vx, vy, wz, current):
    states = SQUARE.module_states((vx, vy, wz), current)
    for state, now in zip(states, current, strict=True):
        assert abs(state.angle - now) <= PI / 2 + 1e-9
    twist = SQUARE.forward([s.angle for s in states], [s.speed for s in states])
    assert twist == pytest.approx((vx, vy, wz), abs=1e-9)


def test_modules_that_fight_give_the_least_squares_twist():
    # two modules pushing forward, two pushing back: the chassis stands
    twist = SQUARE.forward(AHEAD, (10.0, 10.0, -10.0, -10.0))
    assert twist == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)


@pytest.mark.parametrize('bad', [
    {'twist': (math.nan, 0.0, 0.0)}, {'twist': (0.0, 0.0)}, {'current': (0.0,) * 3},
    {'current': (0.0, 0.0, 0.0, math.inf)}, {'measured': (0.0, 0.0, 0.0, math.nan)},
])
def test_bad_values_are_rejected(bad):
    args = {'twist': (1.0, 0.0, 0.0), 'current': AHEAD, **bad}
    measured = args.pop('measured', None)
    with pytest.raises(InputRejectedError):
        SQUARE.module_states(args['twist'], args['current'], measured=measured)


@pytest.mark.parametrize('modules', [
    [SwerveModule(0.2, 0.2, R)],
    [SwerveModule(0.2, 0.2, R), SwerveModule(0.2, 0.2, R)],
])
def test_a_chassis_that_cannot_be_solved_is_refused(modules):
    with pytest.raises(ConfigError):
        SwerveKinematics(modules)


@pytest.mark.parametrize('kwargs', [
    {'x': 0.0, 'y': 0.0, 'radius': 0.0}, {'x': math.nan, 'y': 0.0, 'radius': R},
    {'x': True, 'y': 0.0, 'radius': R},
])
def test_a_bad_module_is_refused(kwargs):
    with pytest.raises(ConfigError):
        SwerveModule(**kwargs)
