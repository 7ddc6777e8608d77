"""/power_limit: checked whole, then run as the hardware's power stage (split robot)."""

import math

import pytest
from rm_base.bridge.errors import PowerLimitRejectedError
from rm_base.bridge.power_limits import RemotePowerLimits, parse_power_limit
from rm_base.control import ChassisPowerModel
from rm_base.hardware import CanHardware

from rm_base import motors as motor_families
from rm_msgs.msg import PowerLimit

WHEELS = ('wheel_fl', 'wheel_fr')


def hardware():
    return CanHardware({
        'buses': {'can0': {'interface': 'virtual', 'channel': 'power-limit-test'}},
        'joints': {name: {'type': 'm3508', 'bus': 'can0', 'id': i + 1}
                   for i, name in enumerate(WHEELS)},
    }, families=motor_families)


def request(**fields):
    values = {'group': 'chassis', 'joints': list(WHEELS), 'k1': 2.96, 'k2': 3.08e-3,
              'static_power_w': 2.8, 'limit_w': 60.0, **fields}
    return PowerLimit(**values)


def test_a_request_becomes_a_stage_and_a_new_limit_changes_only_the_limit():
    hw = hardware()
    limits = RemotePowerLimits(hw)
    limits.apply(parse_power_limit(request(), WHEELS))
    stage = hw.power_limits['chassis']
    assert stage.joints == WHEELS and stage.limit_w == 60.0
    assert stage.model == ChassisPowerModel(2.96, 3.08e-3, 2.8)
    limits.apply(parse_power_limit(request(limit_w=math.inf), WHEELS))
    assert hw.power_limits['chassis'] is stage and stage.limit_w == math.inf


def test_new_joints_or_model_replace_the_stage():
    hw = hardware()
    limits = RemotePowerLimits(hw)
    limits.apply(parse_power_limit(request(), WHEELS))
    first = hw.power_limits['chassis']
    limits.apply(parse_power_limit(request(joints=['wheel_fl'], k1=1.0), WHEELS))
    stage = hw.power_limits['chassis']
    assert stage is not first and stage.joints == ('wheel_fl',)
    assert hw.scheduler.order().count(stage.name) == 1


@pytest.mark.parametrize(
    ('fields', 'match'),
    [
        ({'group': ''}, 'without a group'),
        ({'joints': []}, 'none, or one twice'),
        ({'joints': ['wheel_fl', 'wheel_fl']}, 'none, or one twice'),
        ({'joints': ['wheel_fl', 'arm']}, r"unknown joint\(s\) \['arm'\]"),
        ({'k1': -1.0}, 'k1'),
        ({'k2': math.nan}, 'k2'),
        ({'limit_w': -5.0}, 'limit_w -5.0'),
        ({'limit_w': math.nan}, 'limit_w nan'),
    ],
)
def test_a_bad_request_is_rejected_whole(fields, match):
    with pytest.raises(PowerLimitRejectedError, match=match):
        parse_power_limit(request(**fields), WHEELS)


def test_a_group_the_loop_has_from_elsewhere_is_not_replaced():
    hw = hardware()
    own = hw.add_power_limit('chassis', WHEELS, ChassisPowerModel(1.0, 0.0))  # in-process
    with pytest.raises(PowerLimitRejectedError, match='has a stage of that group already'):
        RemotePowerLimits(hw).apply(parse_power_limit(request(), WHEELS))
    assert hw.power_limits['chassis'] is own
