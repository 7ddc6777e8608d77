"""LocalJointIO: plugin targets set on the actuators directly, the view filled from them."""

import math

import pytest
from rm_base.joints import JointState, JointTarget, Mode
from rm_base.plugin.errors import TargetRejectedError
from rm_base.plugin.node_io import LocalJointIO


class FakeHardware:
    def __init__(self):
        self.commands = []
        self.power_limits = {}

    def add_power_limit(self, group, joints, model):
        self.power_limits[group] = (tuple(joints), model)
        return ('stage', group)

    def remove_power_limit(self, group):
        del self.power_limits[group]

    def set_target(self, name, target):
        if name not in ('wheel_l', 'wheel_r'):
            raise KeyError(name)
        self.commands.append((name, target))

    def states(self, stamp_ns=None):
        stamp = 77 if stamp_ns is None else stamp_ns  # as CanHardware.states
        return [JointState('wheel_l', 1.0, 2.0, 0.5, math.nan, True, 0, 2, 0.4, stamp)]


class FakeNode:
    def get_logger(self):
        return None


def test_targets_go_to_the_actuators_as_validated_values():
    hw = FakeHardware()
    io = LocalJointIO(FakeNode(), hw)
    io.send({'wheel_l': JointTarget.with_velocity(3.0), 'wheel_r': JointTarget.off()}, now=None)
    assert hw.commands == [
        ('wheel_l', JointTarget(Mode.VELOCITY, 0.0, 3.0, 0.0, 0.0, 0.0)),
        ('wheel_r', JointTarget(Mode.OFF, 0.0, 0.0, 0.0, 0.0, 0.0)),
    ]


@pytest.mark.parametrize(
    ('target', 'message'),
    [
        (JointTarget.with_velocity(math.nan), 'joint .wheel_r.: velocity is not a finite'),
        (JointTarget.with_mit(0.0, 0.0, 0.0, -1.0, 0.0), 'joint .wheel_r.: MIT gains must be >= 0'),
    ],
)
def test_when_one_target_is_bad_expect_nothing_set(target, message):
    hw = FakeHardware()
    io = LocalJointIO(FakeNode(), hw)
    with pytest.raises(TargetRejectedError, match=message):
        io.send({'wheel_l': JointTarget.with_velocity(1.0), 'wheel_r': target}, now=None)
    assert hw.commands == []


def test_the_view_holds_every_joint_stamped_with_the_tick():
    io = LocalJointIO(FakeNode(), FakeHardware())
    io.refresh(123)
    state = io.joint_states.get('wheel_l')
    # stamped on the plugins' clock at the tick, not the hardware's
    assert (state.position, state.velocity, state.command, state.stamp_ns) == (1.0, 2.0, 0.4, 123)
    assert state.mode == Mode.VELOCITY and state.online


def test_a_power_limit_runs_in_the_hardware_until_released():
    hw = FakeHardware()
    io = LocalJointIO(FakeNode(), hw)
    assert io.power_limit('chassis', ['wheel_l', 'wheel_r'], 'model') == ('stage', 'chassis')
    assert hw.power_limits == {'chassis': (('wheel_l', 'wheel_r'), 'model')}
    io.release()
    io.release()  # idempotent
    assert hw.power_limits == {}
