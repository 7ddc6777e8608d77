"""AgileX Piper joint MIT frames: vectors A1–A5, check nibble, round trips, errors."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.hardware.errors import ChecksumError, FrameLengthError, ValueRangeError
from rm_base.hardware.protocols.mit import MitCommand
from rm_base.motors.piper import protocol as piper


def h(text):
    return bytes.fromhex(text)


# JointMitCtrl(motor_num, pos_ref, vel_ref, kp, kd, t_ref) -> MitCommand(p, v, kp, kd, t)
@pytest.mark.parametrize(
    ('name', 'joint', 'args', 'limits', 'can_id', 'data'),
    [
        ('A1', 6, (-0.5, 0, 10, 0.8, 0), piper.PIPER_MIT_LIMITS, 0x15F, '7A E0 7F F0 51 94 77 F7'),
        ('A2', 6, (0, 0, 10, 0.8, 0), piper.PIPER_MIT_LIMITS, 0x15F, '7F FF 7F F0 51 94 77 FD'),
        ('A3', 6, (0.5, 0, 10, 0.8, 0), piper.PIPER_MIT_LIMITS, 0x15F, '85 1E 7F F0 51 94 77 F6'),
        (
            'A4',
            1,
            (1.0, 2.0, 20, 1.0, 2.0),
            piper.PIPER_MIT_LIMITS,
            0x15A,
            '8A 3C 85 A0 A3 99 99 F0',
        ),
        (
            'A5',
            1,
            (1.0, 2.0, 20, 1.0, 2.0),
            piper.PIPER_MIT_LIMITS_LEGACY,
            0x15A,
            '8A 3C 85 A0 A3 99 98 D1',
        ),
    ],
)
def test_piper_vectors(name, joint, args, limits, can_id, data):
    assert piper.pack_joint_mit(joint, MitCommand(*args), limits) == (can_id, h(data)), name
    got_joint, cmd = piper.unpack_joint_mit(can_id, h(data), limits)
    assert got_joint == joint
    for got, want, span, bits in zip(
        cmd, args, (25.0, 90.0, 500.0, 10.0, 2 * limits.t_max), (16, 12, 12, 12, 8), strict=True
    ):
        assert want - span / ((1 << bits) - 1) <= got <= want + 1e-9


def test_a1_check_nibble_is_xor_of_bytes_0_to_6():
    # 7A^E0^7F^F0^51^94^77 = 0xA7 -> 7
    assert piper.check_nibble(h('7A E0 7F F0 51 94 77')) == 7


def test_when_check_nibble_wrong_expect_checksum_error():
    with pytest.raises(ChecksumError, match='check 0x8, expected 0x7'):
        piper.unpack_joint_mit(0x15F, h('7A E0 7F F0 51 94 77 F8'))


def test_low_torque_nibble_is_not_covered_by_the_check():
    # byte 7's high nibble is t[3:0]; changing it keeps the frame valid (SDK behaviour)
    piper.unpack_joint_mit(0x15F, h('7A E0 7F F0 51 94 77 07'))


@pytest.mark.parametrize('joint', [0, 7])
def test_when_joint_out_of_range_expect_error(joint):
    with pytest.raises(ValueRangeError, match=f'Piper joint {joint} outside 1..6'):
        piper.pack_joint_mit(joint, MitCommand(0, 0, 0, 0, 0))


def test_unpack_rejects_foreign_ids_and_lengths():
    with pytest.raises(ValueRangeError, match='not a Piper joint MIT id'):
        piper.unpack_joint_mit(0x160, bytes(8))
    with pytest.raises(FrameLengthError, match='8 bytes, got 7'):
        piper.unpack_joint_mit(0x15A, bytes(7))


def test_out_of_range_values_are_clamped_and_nan_rejected():
    _, data = piper.pack_joint_mit(1, MitCommand(99, 99, 999, 99, 99))
    assert data[:7] == h('FF FF FF FF FF FF FF')
    assert data[7] >> 4 == 0xF
    with pytest.raises(ValueRangeError, match='Piper torque nan is not finite'):
        piper.pack_joint_mit(1, MitCommand(0, 0, 0, 0, math.nan))


@given(
    st.integers(1, 6),
    st.tuples(st.integers(0, 0xFFFF), *[st.integers(0, 0xFFF)] * 3, st.integers(0, 0xFF)),
)
def test_round_trip_on_the_integer_grid(joint, ints):
    lim = piper.PIPER_MIT_LIMITS
    q, dq, kp, kd, t = ints
    spans = (
        (-12.5, 12.5, 16, q),
        (-45, 45, 12, dq),
        (0, 500, 12, kp),
        (-5, 5, 12, kd),
        (-8, 8, 8, t),
    )
    # grid values sit exactly on a step; nudge up by a quarter step so truncation is stable
    values = [
        lo + (u + 0.25) * (hi - lo) / ((1 << b) - 1) if u < (1 << b) - 1 else hi
        for lo, hi, b, u in spans
    ]
    can_id, data = piper.pack_joint_mit(joint, MitCommand(*values), lim)
    assert can_id == 0x159 + joint
    assert (data[0] << 8 | data[1], data[2] << 4 | data[3] >> 4) == (q, dq)
    assert ((data[6] & 0xF) << 4) | (data[7] >> 4) == t
    assert piper.unpack_joint_mit(can_id, data, lim)[0] == joint


# --- feedback (piper_sdk docstrings) ---
def test_joint_feedback_layout():
    # joint 3 = 90.000 deg = 90000 = 0x00015F90, joint 4 = -1.5 deg = -1500 = 0xFFFFFA24
    can_id, data = piper.encode_joint_feedback(3, math.radians(90.0), math.radians(-1.5))
    assert (can_id, data) == (0x2A6, h('00 01 5F 90 FF FF FA 24'))
    joint, a, b = piper.decode_joint_feedback(can_id, data)
    assert joint == 3
    assert (math.degrees(a), math.degrees(b)) == pytest.approx((90.0, -1.5))
    assert piper.joint_feedback_id(4) == (0x2A6, 1)
    assert piper.joint_feedback_id(5) == (0x2A7, 0)


def test_high_speed_feedback_layout():
    # speed 1.5 rad/s = 1500 = 0x05DC; current -2.0 A = -2000 = 0xF830; position raw 7
    can_id, data = piper.encode_high_speed_feedback(2, 1.5, -2.0, 7)
    assert (can_id, data) == (0x252, h('05 DC F8 30 00 00 00 07'))
    assert piper.decode_high_speed_feedback(can_id, data) == (2, 1.5, -2.0, 7)


def test_feedback_errors():
    with pytest.raises(ValueRangeError, match='not a Piper joint feedback id'):
        piper.decode_joint_feedback(0x2A8, bytes(8))
    with pytest.raises(FrameLengthError, match='8 bytes, got 6'):
        piper.decode_high_speed_feedback(0x251, bytes(6))
    with pytest.raises(ValueRangeError, match='starts at joint 1, 3 or 5'):
        piper.encode_joint_feedback(2, 0.0, 0.0)
    with pytest.raises(ValueRangeError, match='not finite'):
        piper.encode_high_speed_feedback(1, math.nan, 0.0)


@given(st.integers(0, 2), st.integers(-(2**31), 2**31 - 1), st.integers(-(2**31), 2**31 - 1))
def test_joint_feedback_round_trip(index, a, b):
    data = a.to_bytes(4, 'big', signed=True) + b.to_bytes(4, 'big', signed=True)
    joint, ra, rb = piper.decode_joint_feedback(0x2A5 + index, data)
    assert piper.encode_joint_feedback(joint, ra, rb) == (0x2A5 + index, data)
