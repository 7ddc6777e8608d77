"""ChassisCmd / Twist checking: valid commands pass, bad ones are rejected whole."""

import math

import pytest
from geometry_msgs.msg import Twist
from rm_base.errors import InputRejectedError
from rm_plugins.chassis import ChassisMode, FollowSource, parse_chassis_cmd, parse_vel_cmd
from rm_plugins.chassis.commands import SpeedGear

from rm_msgs.msg import ChassisCmd


def cmd(mode=ChassisCmd.RAW, source='', ax=0.0, ay=0.0, aw=0.0, power=0.0):
    msg = ChassisCmd()
    msg.mode = mode
    msg.follow_source = source
    msg.accel.linear.x, msg.accel.linear.y, msg.accel.angular.z = ax, ay, aw
    msg.power_limit = power
    return msg


@pytest.mark.parametrize('mode', [0, 1, 2, 3, 4])
def test_when_mode_is_a_chassiscmd_constant_expect_the_state_of_that_value(mode):
    assert parse_chassis_cmd(cmd(mode)).mode is ChassisMode(mode)


def test_when_mode_is_unknown_expect_rejected_naming_the_known_modes():
    with pytest.raises(InputRejectedError, match=r'unknown mode 7 \(known: 0=PASSIVE'):
        parse_chassis_cmd(cmd(7))


def test_when_accel_and_power_are_not_positive_expect_none_for_the_configured_default():
    request = parse_chassis_cmd(cmd(ax=2.0, ay=0.0, aw=-1.0, power=-5.0))
    assert request.accel == (2.0, None, None)
    assert request.power_limit is None


def test_when_power_limit_is_positive_expect_it_in_watts():
    assert parse_chassis_cmd(cmd(power=45.0)).power_limit == 45.0


@pytest.mark.parametrize(('source', 'expected'), [('', FollowSource.GIMBAL),
                                                   ('base_link', FollowSource.BASE_LINK),
                                                   ('odom', FollowSource.ODOM)])
def test_when_follow_source_is_known_expect_its_member(source, expected):
    assert parse_chassis_cmd(cmd(source=source)).source is expected


@pytest.mark.parametrize(('gear', 'expected'), [(ChassisCmd.GEAR_NORMAL, SpeedGear.NORMAL),
                                                 (ChassisCmd.GEAR_SLOW, SpeedGear.SLOW),
                                                 (ChassisCmd.GEAR_FAST, SpeedGear.FAST)])
def test_when_speed_gear_is_a_chassiscmd_constant_expect_that_gear(gear, expected):
    msg = cmd()
    msg.speed_gear = gear
    assert parse_chassis_cmd(msg).gear is expected
    assert parse_chassis_cmd(cmd()).gear is SpeedGear.NORMAL  # a command without one


def test_when_speed_gear_is_unknown_expect_rejected_naming_the_gears():
    msg = cmd()
    msg.speed_gear = 9
    with pytest.raises(InputRejectedError, match=r'unknown speed_gear 9 \(known: 0=NORMAL, 1=SLOW'):
        parse_chassis_cmd(msg)


def test_when_follow_source_is_unknown_expect_rejected():
    with pytest.raises(InputRejectedError, match="unknown follow_source 'turret'"):
        parse_chassis_cmd(cmd(source='turret'))


@pytest.mark.parametrize('field', ['ax', 'ay', 'aw', 'power'])
def test_when_a_number_is_nan_or_inf_expect_rejected(field):
    for bad in (math.nan, math.inf):
        with pytest.raises(InputRejectedError, match='must be finite'):
            parse_chassis_cmd(cmd(**{field: bad}))


def test_when_twist_is_finite_expect_vx_vy_wz_and_the_rest_ignored():
    msg = Twist()
    msg.linear.x, msg.linear.y, msg.linear.z, msg.angular.z = 1.0, -0.5, 3.0, 2.0
    msg.angular.x = math.nan  # not a planar component: ignored
    assert parse_vel_cmd(msg) == (1.0, -0.5, 2.0)


def test_when_twist_has_nan_expect_rejected():
    msg = Twist()
    msg.linear.y = math.nan
    with pytest.raises(InputRejectedError, match='must be finite'):
        parse_vel_cmd(msg)


@pytest.mark.parametrize(('field', 'value', 'match'), [
    ('move_x', 1e308, r'move_x 1e\+308 is beyond \+-100'),
    ('move_y', -101.0, r'move_y -101 is beyond \+-100'),
    ('move_yaw', 1e6, r'move_yaw 1e\+06 is beyond'),
])
def test_when_a_move_is_absurd_expect_it_refused_naming_the_field(field, value, match):
    msg = cmd(ChassisCmd.POSITION)
    setattr(msg, field, value)
    with pytest.raises(InputRejectedError, match=match):
        parse_chassis_cmd(msg)
