"""PowerLimitStage: one factor on a group's efforts after their loops, at the loop rate."""

import math

import pytest
from rm_base.control import ChassisPowerModel, estimate_power
from rm_base.hardware.actuators import Mode
from rm_base.hardware.power_stage import PowerLimitStage
from rm_base.motors import actuator_class
from support.hardware import MS, T0, joint
from support.hardware import feed_dji as feed

from rm_base import motors as motor_families

# k1 = 3 W/(N*m)^2 copper loss, no speed losses, 2 W static: at standstill four wheels
# at 2 N*m draw 4 * 3 * 4 + 2 = 50 W.
MODEL = ChassisPowerModel(k1=3.0, k2=0.0, static_power_w=2.0)


def wheels(effort=2.0):
    """Four M3508 in effort mode at effort [N*m], at rest, updated once."""
    out = []
    for i in range(1, 5):
        actuator = actuator_class('m3508')(joint(name=f'w{i}', type='m3508', id=i))
        feed(actuator, T0)
        actuator.set_command(Mode.EFFORT, T0, effort=effort)
        actuator.update(T0, 0.001)
        out.append(actuator)
    return out


def test_when_under_the_limit_expect_the_efforts_unchanged():
    group = wheels()
    stage = PowerLimitStage('chassis', group, MODEL)
    stage.limit_w = 60.0
    before = [a.effort_out for a in group]
    assert stage(T0, 0.001)
    assert [a.effort_out for a in group] == before
    assert stage.last.scale == 1.0


def test_when_over_the_limit_expect_one_factor_on_every_effort_and_the_power_at_it():
    group = wheels()
    stage = PowerLimitStage('chassis', group, MODEL)
    stage.limit_w = 14.0  # 12 s^2 * 4 + 2 = 14  ->  s = 0.5
    before = [a.effort_out for a in group]
    stage(T0, 0.001)
    assert stage.last.scale == pytest.approx(0.5, rel=1e-3)  # of the ESC-rounded efforts
    ratios = [a.effort_out / b for a, b in zip(group, before, strict=True)]
    assert ratios == pytest.approx([0.5] * 4, abs=2e-3)  # the ESC's current steps
    power = estimate_power(MODEL, [a.effort_out for a in group], [0.0] * 4)
    assert power == pytest.approx(14.0, rel=0.01)
    # what goes on the wire is the scaled current
    assert group[0].command_raw == pytest.approx(16384 * 1.0 / 0.3 / 20.0 * 0.5 * 2, rel=0.01)


def test_when_the_group_is_off_expect_nothing_done_and_no_timing():
    group = wheels(effort=0.0)
    stage = PowerLimitStage('chassis', group, MODEL)
    stage.limit_w = 1.0
    assert stage(T0, 0.001) is False
    assert stage.last is None


def test_no_limit_by_default():
    stage = PowerLimitStage('chassis', wheels(), MODEL)
    assert math.isinf(stage.limit_w)
    stage(T0, 0.001)
    assert stage.last.scale == 1.0


def test_scale_output_refuses_a_factor_outside_zero_to_one():
    actuator = wheels()[0]
    with pytest.raises(ValueError, match=r'output scale must be in \[0, 1\]'):
        actuator.scale_output(1.5)
    with pytest.raises(ValueError, match='output scale'):
        actuator.scale_output(math.nan)


def test_a_held_joint_is_not_scaled_back_on():
    actuator = wheels()[0]
    actuator.set_command(Mode.OFF, T0 + MS)
    actuator.update(T0 + MS, 0.001)
    actuator.scale_output(0.5)
    assert actuator.effort_out == 0.0
    assert actuator.command_raw == 0


def test_the_hardware_runs_a_power_limit_after_the_update_and_before_packing(channel):
    from rm_base.hardware import CanHardware
    from rm_base.hardware.errors import HardwareConfigError

    hw = CanHardware({
        'buses': {'can0': {'interface': 'virtual', 'channel': channel}},
        'joints': {f'w{i}': {'type': 'm3508', 'bus': 'can0', 'id': i} for i in range(1, 5)},
    }, families=motor_families)
    with pytest.raises(HardwareConfigError, match=r"unknown joint\(s\) \['nope'\]"):
        hw.add_power_limit('chassis', ['w1', 'nope'], MODEL)
    stage = hw.add_power_limit('chassis', ['w1', 'w2', 'w3', 'w4'], MODEL)
    names = [name for name, _ in hw.scheduler.component_stats()]
    assert names.index('actuators') < names.index('power limit chassis') < names.index('pack')
    with pytest.raises(HardwareConfigError, match='already'):
        hw.add_power_limit('chassis', ['w1'], MODEL)
    hw.remove_power_limit('chassis')
    assert 'power limit chassis' not in [n for n, _ in hw.scheduler.component_stats()]
    assert stage.joints == ('w1', 'w2', 'w3', 'w4')
