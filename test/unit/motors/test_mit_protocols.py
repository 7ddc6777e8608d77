"""MIT frame, Damiao and Cheetah protocols: vectors M1–M4, R1–R3, P1, P2, V1, PF1, C1, C2."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.hardware.errors import FrameLengthError, HardwareConfigError, ValueRangeError
from rm_base.hardware.protocols import mit
from rm_base.hardware.protocols.mit import MitCommand, MitLimits, SystemCommand
from rm_base.motors.cheetah import protocol as cheetah
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.damiao.protocol import DmMode


def h(text):
    return bytes.fromhex(text)


DM4310 = damiao.dm_limits('DM4310')
DM8009 = damiao.dm_limits('DM8009')


# --- float <-> uint ---
def test_float_to_uint_truncates_like_the_c_code():
    # (1.0 + 12.5) * 65535 / 25 = 35388.9 -> 35388 (M2 position)
    assert mit.float_to_uint(1.0, -12.5, 12.5, 16) == 35388
    assert mit.float_to_uint(12.5, -12.5, 12.5, 16) == 65535
    assert mit.float_to_uint(-12.5, -12.5, 12.5, 16) == 0


@pytest.mark.parametrize('bad', [12.6, -12.6, math.nan, math.inf])
def test_when_float_outside_range_expect_error(bad):
    with pytest.raises(ValueRangeError, match='outside'):
        mit.float_to_uint(bad, -12.5, 12.5, 16)


def test_uint_to_float_rejects_values_wider_than_the_field():
    with pytest.raises(ValueRangeError, match='outside the 12-bit field'):
        mit.uint_to_float(4096, -1.0, 1.0, 12)


# --- MIT command vectors ---
@pytest.mark.parametrize(
    ('name', 'limits', 'cmd', 'ints', 'data'),
    [
        ('M1', DM4310, (0, 0, 0, 0, 0), (32767, 2047, 0, 0, 2047), '7F FF 7F F0 00 00 07 FF'),
        (
            'M2',
            DM4310,
            (1.0, 2.0, 10, 0.5, 1.0),
            (35388, 2184, 81, 409, 2252),
            '8A 3C 88 80 51 19 98 CC',
        ),
        (
            'M3',
            DM8009,
            (-math.pi, -10, 50, 2, -20),
            (24532, 1592, 409, 1638, 1289),
            '5F D4 63 81 99 66 65 09',
        ),
        (
            'M4',
            DM4310,
            (12.5, 30, 500, 5, 10),
            (65535, 4095, 4095, 4095, 4095),
            'FF FF FF FF FF FF FF FF',
        ),
        (
            'C1',
            cheetah.CHEETAH_DEFAULT_LIMITS,
            (0, 0, 0, 0, 1.0),
            (32767, 2047, 0, 0, 2161),
            '7F FF 7F F0 00 00 08 71',
        ),
    ],
)
def test_mit_command_vectors(name, limits, cmd, ints, data):
    command = MitCommand(*cmd)
    assert mit.mit_command_uints(command, limits) == ints, name
    assert mit.pack_mit_command(command, limits) == h(data), name
    assert mit.unpack_mit_uints(h(data)) == ints


def test_m3_ids_for_each_mode():
    assert damiao.command_id(3, DmMode.MIT) == 0x003
    assert damiao.command_id(1, DmMode.POS_VEL) == 0x101
    assert damiao.command_id(1, DmMode.VEL) == 0x201
    assert damiao.command_id(1, DmMode.POS_FORCE) == 0x301


def test_when_mit_command_out_of_range_expect_clamping_before_packing():
    # Far beyond every limit: saturates to the all-max frame of M4 instead of wrapping.
    over = MitCommand(100.0, 1e3, 1e4, 50.0, 1e3)
    assert mit.pack_mit_command(over, DM4310) == h('FF FF FF FF FF FF FF FF')
    under = MitCommand(-100.0, -1e3, -1.0, -1.0, -1e3)
    assert mit.pack_mit_command(under, DM4310) == bytes(8)


@pytest.mark.parametrize('field', range(5))
def test_when_mit_command_has_nan_expect_rejection(field):
    values = [0.0] * 5
    values[field] = math.nan
    with pytest.raises(ValueRangeError, match='not finite'):
        mit.pack_mit_command(MitCommand(*values), DM4310)


def test_pack_mit_uints_rejects_wide_fields():
    with pytest.raises(ValueRangeError, match='do not fit'):
        mit.pack_mit_uints(0, 4096, 0, 0, 0)


# --- Damiao feedback ---
@pytest.mark.parametrize(
    ('name', 'limits', 'data', 'expected'),
    [
        # p 32768 -> 32768*25/65535 - 12.5; v 2048 -> 2048*60/4095 - 30; t 2047 -> 2047*20/4095-10
        ('R1', DM4310, '11 80 00 80 07 FF 1E 20', (1, 1, 0.000191, 0.007326, -0.002442, 30, 32)),
        ('R2', DM8009, '23 A2 F8 C0 E1 91 2D 2F', (3, 2, 3.415160, 22.824176, -43.424176, 45, 47)),
        ('R3', DM4310, '00 00 00 00 00 00 00 00', (0, 0, -12.5, -30.0, -10.0, 0, 0)),
    ],
)
def test_damiao_feedback_vectors(name, limits, data, expected):
    fb = damiao.decode_feedback(h(data), limits)
    assert (fb.motor_id, fb.state, fb.t_mos, fb.t_rotor) == (
        expected[0],
        expected[1],
        expected[5],
        expected[6],
    ), name
    assert fb.position == pytest.approx(expected[2], abs=1e-6)
    assert fb.velocity == pytest.approx(expected[3], abs=1e-6)
    assert fb.torque == pytest.approx(expected[4], abs=1e-6)
    again = damiao.encode_feedback(
        fb.motor_id,
        fb.state,
        position=fb.position,
        velocity=fb.velocity,
        torque=fb.torque,
        t_mos=fb.t_mos,
        t_rotor=fb.t_rotor,
        limits=limits,
    )
    assert again == h(data)


def test_damiao_feedback_states():
    assert damiao.DmState(0xC) is damiao.DmState.COIL_OVER_TEMPERATURE
    assert damiao.DmState.ENABLED not in damiao.FAULT_STATES
    assert damiao.DmState.OVERLOAD in damiao.FAULT_STATES


@pytest.mark.parametrize('n', [0, 6, 9])
def test_when_damiao_feedback_length_wrong_expect_error(n):
    with pytest.raises(FrameLengthError, match=f'8 bytes, got {n}'):
        damiao.decode_feedback(bytes(n), DM4310)


def test_damiao_encode_feedback_rejects_bad_fields():
    with pytest.raises(ValueRangeError, match=r'outside 0\.\.15'):
        damiao.encode_feedback(
            16, 1, position=0, velocity=0, torque=0, t_mos=0, t_rotor=0, limits=DM4310
        )
    with pytest.raises(ValueRangeError, match='not finite'):
        damiao.encode_feedback(
            1, 1, position=math.nan, velocity=0, torque=0, t_mos=0, t_rotor=0, limits=DM4310
        )


# --- Damiao other modes ---
@pytest.mark.parametrize(
    ('name', 'can_id', 'motor', 'pos', 'vlim', 'data'),
    [
        ('P1', 0x101, 1, 1.5, 2.0, '00 00 C0 3F 00 00 00 40'),
        ('P2', 0x102, 2, -math.pi / 2, 10.0, 'DB 0F C9 BF 00 00 20 41'),
    ],
)
def test_pos_vel_vectors(name, can_id, motor, pos, vlim, data):
    assert damiao.command_id(motor, DmMode.POS_VEL) == can_id
    assert damiao.pack_pos_vel(pos, vlim) == h(data), name
    p, v = damiao.unpack_pos_vel(h(data))
    assert p == pytest.approx(pos, rel=1e-7)
    assert v == pytest.approx(vlim)


def test_v1_vel_frame_dlc_4_and_padded():
    assert damiao.command_id(1, DmMode.VEL) == 0x201
    assert damiao.pack_vel(-3.0) == h('00 00 40 C0')
    assert damiao.pack_vel(-3.0, pad_to_8=True) == h('00 00 40 C0 00 00 00 00')
    assert damiao.unpack_vel(h('00 00 40 C0')) == -3.0
    assert damiao.unpack_vel(h('00 00 40 C0 00 00 00 00')) == -3.0
    with pytest.raises(FrameLengthError, match='4 or 8 bytes, got 5'):
        damiao.unpack_vel(bytes(5))


def test_pf1_pos_force_frame():
    # vel 5.0 * 100 = 500 = 0x01F4; current 0.5 * 10000 = 5000 = 0x1388
    assert damiao.command_id(1, DmMode.POS_FORCE) == 0x301
    assert damiao.pack_pos_force(1.0, 5.0, 0.5) == h('00 00 80 3F F4 01 88 13')
    assert damiao.unpack_pos_force(h('00 00 80 3F F4 01 88 13')) == (1.0, 5.0, 0.5)


@pytest.mark.parametrize(
    ('args', 'match'),
    [
        ((0.0, -1.0, 0.5), 'velocity -1.0'),
        ((0.0, 1.0, 1.5), 'current 1.5'),
        ((math.nan, 1.0, 0.5), 'not finite'),
    ],
)
def test_pos_force_rejects_out_of_range(args, match):
    with pytest.raises(ValueRangeError, match=match):
        damiao.pack_pos_force(*args)


def test_pos_vel_rejects_nan():
    with pytest.raises(ValueRangeError, match='not finite'):
        damiao.pack_pos_vel(math.inf, 1.0)


# --- system frames ---
@pytest.mark.parametrize(
    ('command', 'last'),
    [
        (SystemCommand.ENABLE, 'FC'),
        (SystemCommand.DISABLE, 'FD'),
        (SystemCommand.SET_ZERO, 'FE'),
        (SystemCommand.CLEAR_ERROR, 'FB'),
    ],
)
def test_system_frames(command, last):
    data = mit.system_frame(command)
    assert data == h('FF FF FF FF FF FF FF ' + last)
    assert mit.parse_system_frame(data) is command


def test_parse_system_frame_returns_none_for_mit_commands():
    assert mit.parse_system_frame(h('FF FF FF FF FF FF FF FF')) is None  # M4, all at max
    assert mit.parse_system_frame(h('7F FF 7F F0 00 00 07 FF')) is None
    assert mit.parse_system_frame(h('FF FF FF FF FF FF FF FA')) is None
    with pytest.raises(FrameLengthError):
        mit.parse_system_frame(bytes(4))
    with pytest.raises(ValueRangeError, match='unknown MIT system command'):
        mit.system_frame(0x12)


def test_system_frame_id_with_and_without_mode_offset():
    assert damiao.system_frame_id(1, DmMode.POS_VEL) == 0x101
    assert damiao.system_frame_id(1, DmMode.POS_VEL, with_mode_offset=False) == 0x001
    assert damiao.system_frame_id(1, DmMode.MIT) == 0x001


# --- limits table ---
def test_model_limits_table_and_overrides():
    assert damiao.dm_limits('dm8009') == MitLimits(12.5, 45.0, 54.0)
    assert damiao.dm_limits('DM10010L').t_max == 200.0
    assert damiao.dm_limits('DM4340', {'v_max': 10.0}).v_max == 10.0
    with pytest.raises(HardwareConfigError, match="unknown Damiao model 'DM9999'"):
        damiao.dm_limits('DM9999')
    with pytest.raises(HardwareConfigError, match='unknown MIT limit'):
        damiao.dm_limits('DM4310', {'vmax': 3.0})
    with pytest.raises(HardwareConfigError, match='p_max must be > 0'):
        MitLimits(0.0, 1.0, 1.0)
    with pytest.raises(HardwareConfigError, match='kd_min must be finite and < kd_max'):
        MitLimits(1.0, 1.0, 1.0, kd_min=6.0)


# --- Cheetah ---
def test_c2_cheetah_reply():
    # p 0x8000: 32768*25/65535-12.5 = 0.000191; v 0x800: 2048*130/4095-65 = 0.015873;
    # t 0x800: 2048*36/4095-18 = 0.004396
    reply = cheetah.decode_reply(h('01 80 00 80 08 00'))
    assert reply.motor_id == 1
    assert reply.position == pytest.approx(0.000191, abs=1e-6)
    assert reply.velocity == pytest.approx(0.015873, abs=1e-6)
    assert reply.torque == pytest.approx(0.004396, abs=1e-6)
    assert reply.bus_voltage is None
    assert cheetah.encode_reply(
        1, position=reply.position, velocity=reply.velocity, torque=reply.torque
    ) == h('01 80 00 80 08 00')


def test_cheetah_reply_with_bus_voltage():
    data = cheetah.encode_reply(0x7F, position=0.0, velocity=0.0, torque=0.0, bus_voltage=24.0)
    assert len(data) == 7
    assert data[6] == 153  # 24 V * 255 / 40 V = 153.0
    assert cheetah.decode_reply(data).bus_voltage == pytest.approx(24.0, abs=40 / 255)
    with pytest.raises(FrameLengthError, match='6 or 7 bytes, got 8'):
        cheetah.decode_reply(bytes(8))


def test_cheetah_has_no_clear_error():
    assert cheetah.cheetah_system_frame(SystemCommand.ENABLE) == h('FF FF FF FF FF FF FF FC')
    with pytest.raises(ValueRangeError, match='no clear-error'):
        cheetah.cheetah_system_frame(SystemCommand.CLEAR_ERROR)


# --- round trips ---
limits_st = st.sampled_from([*damiao.DM_MODEL_LIMITS.values(), cheetah.CHEETAH_DEFAULT_LIMITS])


def _step(span, bits):
    return span / ((1 << bits) - 1)


@given(limits_st, st.data())
def test_mit_command_round_trip_within_one_step(limits, data):
    cmd = MitCommand(
        data.draw(st.floats(-limits.p_max, limits.p_max)),
        data.draw(st.floats(-limits.v_max, limits.v_max)),
        data.draw(st.floats(limits.kp_min, limits.kp_max)),
        data.draw(st.floats(limits.kd_min, limits.kd_max)),
        data.draw(st.floats(-limits.t_max, limits.t_max)),
    )
    back = mit.unpack_mit_command(mit.pack_mit_command(cmd, limits), limits)
    # truncation: decoded value is at most one quantisation step below the input
    tol = (
        _step(2 * limits.p_max, 16),
        _step(2 * limits.v_max, 12),
        _step(limits.kp_max, 12),
        _step(limits.kd_max - limits.kd_min, 12),
        _step(2 * limits.t_max, 12),
    )
    for got, want, t in zip(back, cmd, tol, strict=True):
        assert want - t * 1.0001 <= got <= want + 1e-9 * max(1.0, abs(want))


@given(st.tuples(st.integers(0, 0xFFFF), *[st.integers(0, 0xFFF)] * 4))
def test_mit_uints_round_trip(ints):
    assert mit.unpack_mit_uints(mit.pack_mit_uints(*ints)) == ints


@given(
    limits_st,
    st.integers(0, 15),
    st.integers(0, 15),
    st.integers(0, 0xFFFF),
    st.integers(0, 0xFFF),
    st.integers(0, 0xFFF),
    st.integers(0, 255),
    st.integers(0, 255),
)
def test_damiao_feedback_round_trip_is_exact_on_the_grid(limits, mid, state, q, dq, tau, tm, tr):
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    data = damiao.encode_feedback(
        mid,
        state,
        position=mit.uint_to_float(q, -p, p, 16),
        velocity=mit.uint_to_float(dq, -v, v, 12),
        torque=mit.uint_to_float(tau, -t, t, 12),
        t_mos=tm,
        t_rotor=tr,
        limits=limits,
    )
    fb = damiao.decode_feedback(data, limits)
    assert (fb.motor_id, fb.state, fb.t_mos, fb.t_rotor) == (mid, state, tm, tr)
    # nearest rounding on the device side makes the grid round trip exact
    assert (data[1] << 8) | data[2] == q
    assert (data[3] << 4) | (data[4] >> 4) == dq
    assert ((data[4] & 0xF) << 8) | data[5] == tau


@given(st.floats(-1e6, 1e6, width=32), st.floats(-1e6, 1e6, width=32))
def test_pos_vel_round_trip_exact_for_float32(pos, vlim):
    assert damiao.unpack_pos_vel(damiao.pack_pos_vel(pos, vlim)) == (pos, vlim)


@given(st.floats(-1e3, 1e3, width=32), st.integers(0, 0xFFFF), st.integers(0, 10000))
def test_pos_force_round_trip(pos, v_raw, i_raw):
    data = damiao.pack_pos_force(pos, v_raw / 100, i_raw / 10000)
    assert damiao.unpack_pos_force(data) == (pos, v_raw / 100, i_raw / 10000)


@given(st.integers(0, 255), st.integers(0, 0xFFFF), st.integers(0, 0xFFF), st.integers(0, 0xFFF))
def test_cheetah_reply_round_trip_on_the_grid(mid, q, dq, tau):
    lim = cheetah.CHEETAH_DEFAULT_LIMITS
    data = bytes((mid, q >> 8, q & 0xFF, dq >> 4, ((dq & 0xF) << 4) | (tau >> 8), tau & 0xFF))
    r = cheetah.decode_reply(data, lim)
    again = cheetah.encode_reply(mid, position=r.position, velocity=r.velocity, torque=r.torque)
    assert again == data
    vb = cheetah.encode_reply(
        mid,
        position=r.position,
        velocity=r.velocity,
        torque=r.torque,
        bus_voltage=cheetah.decode_reply(data + b'\x99').bus_voltage,
    )
    assert vb == data + b'\x99'
