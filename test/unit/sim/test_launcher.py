"""The simulated launcher: which trigger pushes leave the muzzle as shots."""

import math
from types import SimpleNamespace

import pytest
from rm_base.sim import Joint, Launcher, SimConfigError
from rm_base.sim.body_config import launcher_from_config

SLOT = 2.0 * math.pi / 8
PHASE = 0.55


def motor(angle=0.0, velocity=0.0):
    return SimpleNamespace(model=SimpleNamespace(angle=angle, velocity=velocity))


@pytest.fixture
def parts():
    trigger, left, right = motor(), motor(velocity=400.0), motor(velocity=-400.0)
    launcher = Launcher(
        Joint(trigger), [Joint(left), Joint(right, -1.0)], slots=8, fire_phase=PHASE,
        speed_ratio=0.0385,
    )
    return launcher, trigger, left, right


def test_a_pocket_turned_past_the_firing_point_is_one_shot_at_the_wheels_speed(parts):
    launcher, trigger, _, _ = parts
    trigger.model.angle = PHASE - 0.01
    assert launcher.update(1) == []
    trigger.model.angle = PHASE + 0.01
    (shot,) = launcher.update(2)
    assert shot.time_ns == 2 and shot.speed_mps == pytest.approx(0.0385 * 400.0)
    assert launcher.shots == 1


def test_turning_back_and_forward_again_fires_no_pocket_twice(parts):
    launcher, trigger, _, _ = parts
    for angle in (PHASE + 0.1, PHASE - 0.3, PHASE + 0.1, PHASE + SLOT - 0.01):
        trigger.model.angle = angle
        launcher.update(0)
    assert launcher.shots == 1
    trigger.model.angle = PHASE + SLOT + 0.01
    assert len(launcher.update(0)) == 1


def test_two_pockets_in_one_update_are_two_shots(parts):
    launcher, trigger, _, _ = parts
    trigger.model.angle = PHASE + SLOT + 0.01
    assert len(launcher.update(0)) == 2


def test_a_ball_pushed_with_the_wheels_stopped_is_a_dud_not_a_shot(parts):
    launcher, trigger, left, right = parts
    left.model.velocity = right.model.velocity = 0.0
    trigger.model.angle = PHASE + 0.01
    assert launcher.update(0) == []
    assert (launcher.shots, launcher.duds) == (0, 1)


def test_config_builds_the_joints_from_motor_names():
    devices = {name: motor() for name in ('trigger', 'fl', 'fr')}
    launcher = launcher_from_config(
        {'trigger': {'motor': 'trigger'}, 'friction_motors': ['fl', 'fr'],
         'friction_directions': [1, -1], 'slots': 6, 'fire_phase': 0.7, 'speed_ratio': 0.03,
         'calibre': 42},
        devices,
    )
    assert launcher.calibre == 42 and launcher.slot_angle == pytest.approx(math.pi / 3)
    assert [j.direction for j in launcher.friction] == [1.0, -1.0]
    assert launcher.devices == (devices['trigger'], devices['fl'], devices['fr'])


@pytest.mark.parametrize(
    ('change', 'message'),
    [
        ({'slots': 0}, 'slots'),
        ({'fire_phase': 1.0}, 'fire_phase'),
        ({'calibre': 20}, 'calibre'),
        ({'friction_motors': ['fl', 'nope']}, 'nope'),
        ({'friction_directions': [1, -1]}, 'friction_directions'),
        ({'speed_ratio': float('nan')}, 'speed_ratio'),
        ({'barrel': 1}, 'unknown key'),
        ({'trigger': None}, 'trigger'),
    ],
)
def test_bad_config_is_refused_naming_the_key(change, message):
    config = {'trigger': {'motor': 'trigger'}, 'friction_motors': ['fl'], 'slots': 8,
              'fire_phase': 0.5, 'speed_ratio': 0.03, **change}
    if change.get('trigger', 0) is None:
        del config['trigger']
    with pytest.raises(SimConfigError, match=message):
        launcher_from_config(config, {name: motor() for name in ('trigger', 'fl')})
