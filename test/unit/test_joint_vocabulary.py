"""rm_base.joints: the one check every joint target passes where it enters."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
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


_FIELD_VALUES = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.integers(-3, 3), st.booleans(),
    st.just('1.0'), st.just(np.float32(0.5)),
)


@given(mode=st.one_of(st.sampled_from(Mode), st.integers(-1, 6)),
       fields=st.one_of(st.tuples(*[_FIELD_VALUES] * 5), st.tuples(*[st.floats()] * 5)))
def test_checked_agrees_with_the_field_by_field_check(mode, fields):
    # checked() returns an already valid target as it is; that must change no verdict.
    position, velocity, effort, kp, kd = fields
    target = JointTarget(mode, position, velocity, effort, kp, kd)
    try:
        expected = check_target(
            mode, position=position, velocity=velocity, effort=effort, kp=kp, kd=kd
        )
    except InvalidTargetError as err:
        with pytest.raises(InvalidTargetError) as info:
            checked(target)
        assert info.value.problem is err.problem
    else:
        got = checked(target)
        assert got == expected and got.mode is expected.mode
        assert all(type(getattr(got, name)) is float
                   for name in ('position', 'velocity', 'effort', 'kp', 'kd'))


def test_a_valid_target_is_passed_on_as_it_is():
    target = JointTarget.with_mit(1e308, 1e308, 0.0, 1.0, 0.5)  # sums past inf, still valid
    assert checked(target) == target
    target = JointTarget.with_velocity(2.0)
    assert checked(target) is target


def test_a_state_without_a_stamp_was_never_measured():
    state = JointState('yaw', 0.1, 0.0, 0.0, math.nan, False, 0, Mode.OFF, 0.0)
    assert state.stamp_ns == 0
