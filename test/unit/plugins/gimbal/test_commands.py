"""parse_gimbal_cmd: a GimbalCmd is checked once into a GimbalRequest, or refused with why."""

import math

import pytest
from rm_base.errors import InputRejectedError
from rm_plugins.gimbal.commands import GimbalMode, GimbalRequest, parse_gimbal_cmd

from rm_msgs.msg import GimbalCmd


def cmd(mode, rates=(0.0, 0.0), point=(0.0, 0.0, 0.0), frame='odom', speed=0.0):
    msg = GimbalCmd(mode=mode, rate_yaw=rates[0], rate_pitch=rates[1], bullet_speed=speed)
    msg.target.point.x, msg.target.point.y, msg.target.point.z = point
    msg.target.header.frame_id = frame
    return msg


def test_the_modes_are_the_messages_constants():
    assert [m.value for m in GimbalMode] == [GimbalCmd.PASSIVE, GimbalCmd.RATE, GimbalCmd.TRACK]


@pytest.mark.parametrize(
    ('msg', 'expected'),
    [
        (cmd(GimbalCmd.PASSIVE, rates=(math.nan, 0.0)), GimbalRequest(GimbalMode.PASSIVE)),
        (cmd(GimbalCmd.RATE, rates=(1.0, -0.5)), GimbalRequest(GimbalMode.RATE, (1.0, -0.5))),
        (
            cmd(GimbalCmd.TRACK, point=(3.0, 1.0, 0.2), frame='base_link', speed=15.0),
            GimbalRequest(GimbalMode.TRACK, target=(3.0, 1.0, 0.2), frame='base_link',
                          bullet_speed=15.0),
        ),
    ],
    ids=['passive-ignores-the-rest', 'rate', 'track'],
)
def test_a_valid_command_becomes_its_request(msg, expected):
    assert parse_gimbal_cmd(msg) == expected


@pytest.mark.parametrize(
    ('msg', 'match'),
    [
        (cmd(7), r'unknown mode 7 \(known: 0=PASSIVE, 1=RATE, 2=TRACK\)'),
        (cmd(GimbalCmd.RATE, rates=(0.0, math.inf)), 'rate_yaw and rate_pitch must be finite'),
        (cmd(GimbalCmd.TRACK, point=(math.nan, 0.0, 0.0)), 'must be finite'),
        (cmd(GimbalCmd.TRACK, point=(1.0, 0.0, 0.0), speed=math.nan), 'must be finite'),
        (cmd(GimbalCmd.TRACK, point=(1e4, 0.0, 0.0)), 'beyond 1000 m / 100 m/s'),
        (cmd(GimbalCmd.TRACK, point=(1.0, 0.0, 0.0), speed=-200.0), 'beyond 1000 m'),
    ],
)
def test_a_bad_command_is_refused_with_the_reason(msg, match):
    with pytest.raises(InputRejectedError, match=match):
        parse_gimbal_cmd(msg)
