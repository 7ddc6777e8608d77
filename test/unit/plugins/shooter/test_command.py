"""ShootCmd checks and the shooter's config invariants."""

import math

import pytest
from rm_base.errors import ConfigError, InputRejectedError
from rm_plugins.shooter import ShooterConfig, ShootMode, parse_shoot_cmd
from rm_plugins.shooter.config import HeatParams, JamParams

from rm_msgs.msg import ShootCmd


def cmd(**fields):
    return ShootCmd(**fields)


def test_when_push_is_valid_expect_every_field():
    command = parse_shoot_cmd(cmd(mode=ShootCmd.PUSH, speed=15.0, hz=5.0, num=5, burst_id=9))
    assert command.mode is ShootMode.PUSH
    assert (command.speed, command.hz, command.num, command.burst_id) == (15.0, 5.0, 5, 9)


def test_when_passive_expect_speed_and_rate_not_needed():
    assert parse_shoot_cmd(cmd(mode=ShootCmd.PASSIVE)).mode is ShootMode.PASSIVE


@pytest.mark.parametrize(
    ('fields', 'match'),
    [
        ({'mode': 3}, r'unknown mode 3 \(known: 0=PASSIVE, 1=READY, 2=PUSH\)'),
        ({'mode': ShootCmd.READY, 'speed': math.nan}, 'speed must be a finite number'),
        ({'mode': ShootCmd.PASSIVE, 'speed': math.inf}, 'speed must be a finite number'),
        ({'mode': ShootCmd.READY, 'speed': -1.0}, 'speed must be >= 0'),
        ({'mode': ShootCmd.READY, 'speed': 0.0}, 'READY needs a bullet speed > 0'),
        ({'mode': ShootCmd.PUSH, 'speed': 15.0, 'hz': 0.0}, 'PUSH needs a firing rate hz > 0'),
        ({'mode': ShootCmd.PUSH, 'speed': 15.0, 'hz': math.nan}, 'hz must be a finite'),
    ],
)
def test_when_a_command_is_bad_expect_it_rejected_with_the_reason(fields, match):
    with pytest.raises(InputRejectedError, match=match):
        parse_shoot_cmd(cmd(**fields))


def config(**changes):
    values = {
        'friction_joints': ('friction_l', 'friction_r'),
        'friction_directions': (1.0, 1.0),
        'trigger_joint': 'trigger',
        'trigger_direction': 1.0,
        'bullet_speeds': (15.0, 30.0),
        'wheel_speeds': (470.0, 780.0),
        'friction_tolerance': 25.0,
        'slots': 8,
        'feed_speed': 4.0,
        'step_speed': 12.0,
        'step_tolerance': 0.05,
        'max_hz': 10.0,
        'limit_switch': 'ball_switch',
        'switch_timeout': 0.2,
        'switch_debounce': 0.05,
        'jam': JamParams(effort=1.0, speed=0.5, time=0.15),
        'reverse_angle': 0.4,
        'block_timeout': 0.3,
        'jam_retries': 3,
        'state_rate': 50.0,
        'heat': HeatParams(),
    }
    values.update(changes)
    return ShooterConfig(**values)


def test_when_the_config_is_consistent_expect_the_slot_angle():
    assert config().slot_angle == pytest.approx(math.pi / 4)  # 2*pi / 8 pockets


@pytest.mark.parametrize(
    ('changes', 'match'),
    [
        ({'friction_directions': (1.0,)}, 'friction_directions has 1 entries for 2'),
        ({'friction_directions': (1.0, 0.5)}, r'must be \+1 or -1'),
        ({'trigger_direction': 2.0}, r'must be \+1 or -1'),
        ({'trigger_joint': 'friction_l'}, 'also a friction joint'),
        ({'wheel_speeds': (780.0, 470.0)}, 'must increase'),
        # Half a slot of 2*pi/8 is 0.393 rad: a tolerance that wide could count half a step.
        ({'step_tolerance': 0.4}, 'below half a slot'),
        ({'friction_joints': (), 'friction_directions': ()}, 'at least one friction wheel'),
    ],
)
def test_when_the_config_is_inconsistent_expect_a_config_error(changes, match):
    with pytest.raises(ConfigError, match=match):
        config(**changes)
