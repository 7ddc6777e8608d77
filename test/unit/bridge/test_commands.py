"""/actuator_cmd validation: a message is applied whole or rejected whole."""

import math

import pytest
from rm_base.bridge.commands import (
    check_stamp,
    check_states_stamp,
    first_states_stamp,
    parse_actuator_cmd,
)
from rm_base.bridge.errors import ActuatorCmdRejectedError, Rejection
from rm_base.joints import JointTarget, Mode

from rm_msgs.msg import ActuatorCmd

JOINTS = frozenset({'fl', 'fr', 'yaw'})


def cmd(names=('fl', 'fr'), mode=2, **columns):
    msg = ActuatorCmd()
    n = len(names)
    msg.name = list(names)
    msg.mode = columns.pop('modes', [mode] * n)
    for field in ('position', 'velocity', 'effort', 'kp', 'kd'):
        setattr(msg, field, columns.pop(field, [0.0] * n))
    assert not columns
    return msg


def test_a_well_formed_message_gives_one_target_per_entry_in_order():
    msg = cmd(
        ('yaw', 'fl'),
        modes=[4, 2],
        position=[0.5, 0.0],
        velocity=[0.1, 3.0],
        effort=[0.2, 0.0],
        kp=[20.0, 0.0],
        kd=[1.0, 0.0],
    )
    assert parse_actuator_cmd(msg, JOINTS) == [
        ('yaw', JointTarget(Mode.MIT, 0.5, 0.1, 0.2, 20.0, 1.0)),
        ('fl', JointTarget(Mode.VELOCITY, 0.0, 3.0, 0.0, 0.0, 0.0)),
    ]


def test_an_empty_message_is_well_formed():
    assert parse_actuator_cmd(ActuatorCmd(), JOINTS) == []


@pytest.mark.parametrize(
    ('msg', 'reason', 'text'),
    [
        (cmd(velocity=[1.0]), Rejection.LENGTH_MISMATCH, '2 names but 1 velocity'),
        (cmd(modes=[2]), Rejection.LENGTH_MISMATCH, '2 names but 1 mode'),
        (cmd(('fl', 'fl')), Rejection.DUPLICATE_JOINT, "named twice: \\['fl'\\]"),
        (cmd(('fl', 'rear')), Rejection.UNKNOWN_JOINT, "unknown joint\\(s\\) \\['rear'\\]"),
        (cmd(modes=[2, 5]), Rejection.UNKNOWN_MODE, 'fr: unknown mode 5'),
        (cmd(velocity=[1.0, math.nan]), Rejection.NON_FINITE, 'fr: velocity is not a finite'),
        (cmd(effort=[math.inf, 0.0]), Rejection.NON_FINITE, 'fl: effort is not .*: inf'),
        # a NaN in a field the mode does not use still rejects: it never reaches a motor
        (cmd(kp=[0.0, -math.inf]), Rejection.NON_FINITE, 'fr: kp is not a finite number: -inf'),
        (cmd(mode=4, kd=[0.0, -1.0]), Rejection.NEGATIVE_GAIN, 'kd=-1.0'),
    ],
)
def test_a_malformed_message_is_rejected_whole_with_its_reason(msg, reason, text):
    with pytest.raises(ActuatorCmdRejectedError, match=text) as info:
        parse_actuator_cmd(msg, JOINTS)
    assert info.value.reason is reason


NOW_NS = 1_800_000_000_000_000_000


def stamped(age_s: float) -> ActuatorCmd:
    msg = ActuatorCmd()
    stamp_ns = NOW_NS - round(age_s * 1e9)
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
    return msg


@pytest.mark.parametrize(
    ('age_s', 'age_ns'),
    [
        (0.06, 60_000_000),  # its timeout runs from the stamp: 40 ms left
        (0.0, 0),
        (-0.02, 0),  # slightly ahead (clocks of two processes): counted from now
    ],
)
def test_when_a_stamp_is_within_the_timeout_expect_its_age(age_s, age_ns):
    assert check_stamp(stamped(age_s), NOW_NS, 0.1) == age_ns


def test_when_unstamped_expect_age_zero():
    assert check_stamp(ActuatorCmd(), NOW_NS, 0.1) == 0


@pytest.mark.parametrize(('age_s', 'text'), [(0.2, '0.200 s old'), (-0.2, '0.200 s in the future')])
def test_when_a_stamp_is_beyond_the_timeout_expect_stale(age_s, text):
    with pytest.raises(ActuatorCmdRejectedError, match=text) as info:
        check_stamp(stamped(age_s), NOW_NS, 0.1)
    assert info.value.reason is Rejection.STALE


FIRST_NS = NOW_NS - 2_000_000_000  # this bridge published its first states 2 s ago


def from_states(stamp_ns: int) -> ActuatorCmd:
    msg = ActuatorCmd()
    msg.states_stamp.sec, msg.states_stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
    return msg


@pytest.mark.parametrize(
    ('stamp_ns', 'first_ns'),
    [
        (0, FIRST_NS),  # not computed from states: a hand-written command
        (0, None),
        (FIRST_NS, FIRST_NS),  # from this bridge's very first states
        (FIRST_NS + 5_000_000, FIRST_NS),
    ],
)
def test_targets_from_this_bridges_states_or_from_none_pass(stamp_ns, first_ns):
    check_states_stamp(from_states(stamp_ns), first_ns)


@pytest.mark.parametrize(
    ('stamp_ns', 'first_ns', 'text'),
    [
        (FIRST_NS - 1_000_000, FIRST_NS, '0.001 s older than this bridge.s first'),
        (FIRST_NS - 1, FIRST_NS, '0.000 s older'),
        (FIRST_NS, None, 'this bridge has sent none yet'),
    ],
)
def test_targets_from_states_before_this_bridges_first_are_rejected(stamp_ns, first_ns, text):
    with pytest.raises(ActuatorCmdRejectedError, match=text) as info:
        check_states_stamp(from_states(stamp_ns), first_ns)
    assert info.value.reason is Rejection.OLD_STATES


@pytest.mark.parametrize(
    ('first_ns', 'stamp_ns', 'counted_from'),
    [
        (None, 500, 500),  # the first states published
        (500, 700, 500),  # later states: still counted from the first
        (500, 300, 300),  # the clock went back (simulated time replayed): anew
    ],
)
def test_a_bridges_states_count_from_its_first_stamp(first_ns, stamp_ns, counted_from):
    assert first_states_stamp(first_ns, stamp_ns) == counted_from
