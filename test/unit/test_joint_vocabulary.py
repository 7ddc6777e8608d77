"""rm_base.joints: the one check every joint target passes where it enters."""

import math

import numpy as np
import pytest
from rm_base.joints import (
    InvalidTargetError,
    JointState,
    JointTarget,
    Mode,
    TargetProblem,
    check_target,
    checked,
)


def test_a_valid_target_comes_back_with_a_mode_and_floats():
    target = check_target(4, position=1, velocity=0.5, effort=0.0, kp=20, kd=1.0)
    assert target == JointTarget(Mode.MIT, 1.0, 0.5, 0.0, 20.0, 1.0)
    assert target.mode is Mode.MIT and type(target.position) is float


@pytest.mark.parametrize(
    ('mode', 'fields', 'problem'),
    [
        (9, {}, TargetProblem.UNKNOWN_MODE),
        (True, {}, TargetProblem.UNKNOWN_MODE),  # a bool is not a mode
        ('velocity', {}, TargetProblem.UNKNOWN_MODE),
        (Mode.EFFORT, {'effort': math.nan}, TargetProblem.NON_FINITE),
        (Mode.EFFORT, {'effort': -math.inf}, TargetProblem.NON_FINITE),
        (Mode.EFFORT, {'effort': True}, TargetProblem.NON_FINITE),  # nor a number
        (Mode.EFFORT, {'effort': '1.0'}, TargetProblem.NON_FINITE),
        (Mode.MIT, {'kd': -0.1}, TargetProblem.NEGATIVE_GAIN),
    ],
)
def test_an_invalid_target_is_refused_with_what_is_wrong(mode, fields, problem):
    with pytest.raises(InvalidTargetError) as info:
        check_target(mode, **fields)
    assert info.value.problem is problem


def test_numpy_scalars_are_numbers():
    target = check_target(Mode.VELOCITY, velocity=np.float32(1.5))
    assert target.velocity == 1.5 and type(target.velocity) is float


def test_a_target_built_elsewhere_is_checked_field_by_field():
    assert checked(JointTarget.with_velocity(2)) == JointTarget(Mode.VELOCITY, velocity=2.0)
    with pytest.raises(InvalidTargetError, match='not a JointTarget'):
        checked((Mode.VELOCITY, 2.0))
    with pytest.raises(InvalidTargetError, match='velocity is not a finite number'):
        checked(JointTarget.with_velocity(math.inf))


def test_a_state_without_a_stamp_was_never_measured():
    state = JointState('yaw', 0.1, 0.0, 0.0, math.nan, False, 0, Mode.OFF, 0.0)
    assert state.stamp_ns == 0
