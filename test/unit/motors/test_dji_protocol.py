"""DJI C620/C610/GM6020 protocol: docs/PROTOCOLS.md vectors D1–D5, F1–F3, round trips, errors."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.hardware.errors import FrameLengthError, HardwareConfigError, ValueRangeError
from rm_base.motors.dji import protocol as dji
from rm_base.motors.dji.protocol import DjiKind


def h(text):
    return bytes.fromhex(text)


# --- command vectors ---
@pytest.mark.parametrize(
    ('name', 'raws', 'expected'),
    [
        ('D1', [1000, -1000, 16384, -16384], '03 E8 FC 18 40 00 C0 00'),
        ('D2', [4096, 0, 0, 2500], '10 00 00 00 00 00 09 C4'),
        ('D3', [25000, -12345, 0, -30000], '61 A8 CF C7 00 00 8A D0'),
        ('D4', [8192, -8192], '20 00 E0 00 00 00 00 00'),
        ('D5', [-1, 256, 255], 'FF FF 01 00 00 FF 00 00'),
    ],
)
def test_command_vectors(name, raws, expected):
    data = dji.pack_command(raws)
    assert data == h(expected), name
    assert list(dji.unpack_command(data)) == raws + [0] * (4 - len(raws))


def test_d2_frame_built_from_amps_and_slots():
    # C620 id 1: 5 A * 16384/20 = 4096; C610 id 4: 2.5 A * 10000/10 = 2500; both on 0x200.
    c620 = dji.make_dji_spec('c620')
    c610 = dji.make_dji_spec('c610')
    assert c620.command_slot(1) == (0x200, 0)
    assert c610.command_slot(4) == (0x200, 3)
    raws = [0, 0, 0, 0]
    raws[0] = c620.raw_from_si(5.0)
    raws[3] = c610.raw_from_si(2.5)
    assert dji.pack_command(raws) == h('10 00 00 00 00 00 09 C4')


def test_d4_gm6020_current_mode_with_the_safe_3a_scale():
    # ±1.5 A at 3 A per 16384 -> ±8192; with the 1.62 A scale 1.5 A -> 15170 (docs/PROTOCOLS.md).
    spec = dji.make_dji_spec(DjiKind.GM6020_CURRENT)
    assert spec.command_slot(1) == (0x1FE, 0)
    assert spec.command_slot(2) == (0x1FE, 1)
    assert dji.pack_command([spec.raw_from_si(1.5), spec.raw_from_si(-1.5)]) == h(
        '20 00 E0 00 00 00 00 00'
    )
    alt = dji.make_dji_spec('gm6020_current', si_per_raw=1.62 / 16384)
    assert alt.raw_from_si(1.5) == 15170


def test_d3_d5_gm6020_voltage_frame_ids():
    spec = dji.make_dji_spec('gm6020_voltage')
    assert [spec.command_slot(i) for i in (1, 4, 5, 7)] == [
        (0x1FF, 0),
        (0x1FF, 3),
        (0x2FF, 0),
        (0x2FF, 2),
    ]


# --- feedback vectors ---
@pytest.mark.parametrize(
    ('name', 'kind', 'can_id', 'esc_id', 'data', 'expected'),
    [
        ('F1', 'c620', 0x201, 1, '1F FF 03 E8 FC 18 32 00', (8191, 1000, -1000, 50)),
        ('F2', 'gm6020_voltage', 0x205, 1, '10 00 FF 9C 01 F4 28 00', (4096, -100, 500, 40)),
        ('F3', 'c610', 0x207, 7, '00 00 27 10 EC 78 00 00', (0, 10000, -5000, None)),
    ],
)
def test_feedback_vectors(name, kind, can_id, esc_id, data, expected):
    spec = dji.make_dji_spec(kind)
    assert spec.feedback_id(esc_id) == can_id
    assert spec.esc_id_from_feedback(can_id) == esc_id
    fb = dji.decode_feedback(h(data), has_temperature=spec.has_temperature)
    assert tuple(fb) == expected, name
    assert dji.encode_feedback(*fb) == h(data)


def test_f1_physical_values():
    fb = dji.decode_feedback(h('1F FF 03 E8 FC 18 32 00'))
    # 8191 ticks * 360/8192 = 359.956 deg
    assert math.degrees(fb.angle_ticks * dji.RAD_PER_TICK) == pytest.approx(359.956, abs=1e-3)
    # -1000 raw * 20/16384 = -1.220703 A
    assert dji.make_dji_spec('c620').feedback_amps(fb.current_raw) == pytest.approx(-1.220703)


def test_f3_c610_has_no_temperature_and_10a_scale():
    spec = dji.make_dji_spec('c610')
    fb = dji.decode_feedback(h('00 00 27 10 EC 78 00 00'), has_temperature=False)
    assert fb.temperature_c is None
    assert spec.feedback_amps(fb.current_raw) == pytest.approx(-5.0)  # -5000 * 10/10000


# --- ids, limits, config ---
@pytest.mark.parametrize(
    ('kind', 'esc_id', 'slot', 'fb'),
    [
        ('c620', 1, (0x200, 0), 0x201),
        ('c620', 4, (0x200, 3), 0x204),
        ('c620', 5, (0x1FF, 0), 0x205),
        ('c610', 8, (0x1FF, 3), 0x208),
        ('gm6020_voltage', 7, (0x2FF, 2), 0x20B),
        ('gm6020_current', 5, (0x2FE, 0), 0x209),
    ],
)
def test_boundary_ids(kind, esc_id, slot, fb):
    assert dji.command_slot(kind, esc_id) == slot
    assert dji.feedback_id(kind, esc_id) == fb


@pytest.mark.parametrize(('kind', 'bad_id'), [('c620', 0), ('c620', 9), ('gm6020_voltage', 8)])
def test_when_id_out_of_range_expect_value_range_error(kind, bad_id):
    with pytest.raises(ValueRangeError, match=f'ESC id {bad_id} out of range'):
        dji.command_slot(kind, bad_id)


def test_when_kind_unknown_expect_config_error():
    with pytest.raises(HardwareConfigError, match="unknown DJI kind 'c630'"):
        dji.make_dji_spec('c630')


@pytest.mark.parametrize(
    ('kind', 'limit'),
    [('c620', 16384), ('c610', 10000), ('gm6020_voltage', 25000), ('gm6020_current', 16384)],
)
def test_raw_from_si_clamps_to_the_kind_limit(kind, limit):
    spec = dji.make_dji_spec(kind)
    assert spec.raw_limit == limit
    assert spec.raw_from_si(1e6) == limit
    assert spec.raw_from_si(-1e6) == -limit


def test_gm6020_voltage_limit_is_configurable_up_to_30000_only():
    assert dji.make_dji_spec('gm6020_voltage', raw_limit=30000).raw_from_si(100.0) == 30000
    with pytest.raises(HardwareConfigError, match='raw_limit 30001 out of range'):
        dji.make_dji_spec('gm6020_voltage', raw_limit=30001)
    with pytest.raises(HardwareConfigError, match='si_per_raw must be > 0'):
        dji.make_dji_spec('c620', si_per_raw=-1.0)


@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_when_si_command_not_finite_expect_rejection(bad):
    with pytest.raises(ValueRangeError, match='not finite'):
        dji.make_dji_spec('c620').raw_from_si(bad)


def test_full_scale_commands_pack():
    # +-16384 (C620 max) and int16 extremes fit the frame.
    assert dji.pack_command([16384, -16384, 32767, -32768]) == h('40 00 C0 00 7F FF 80 00')


@pytest.mark.parametrize(
    ('raws', 'error', 'match'),
    [
        ([0, 0, 0, 0, 0], FrameLengthError, '4 slots, got 5'),
        ([40000], ValueRangeError, 'raw 40000'),
        ([1.5], ValueRangeError, 'must be an int'),
    ],
)
def test_when_command_malformed_expect_error(raws, error, match):
    with pytest.raises(error, match=match):
        dji.pack_command(raws)


def test_pack_command_applies_an_explicit_limit():
    with pytest.raises(ValueRangeError, match='outside ±16384'):
        dji.pack_command([16385], limit=16384)


@pytest.mark.parametrize('n', [0, 7, 9])
def test_when_frame_length_wrong_expect_frame_length_error(n):
    with pytest.raises(FrameLengthError, match=f'8 bytes, got {n}'):
        dji.decode_feedback(bytes(n))
    with pytest.raises(FrameLengthError, match=f'8 bytes, got {n}'):
        dji.unpack_command(bytes(n))


def test_when_feedback_angle_above_8191_expect_error():
    with pytest.raises(ValueRangeError, match='angle 8192'):
        dji.decode_feedback(h('20 00 00 00 00 00 00 00'))
    with pytest.raises(ValueRangeError, match='angle 8192'):
        dji.encode_feedback(8192, 0, 0, 0)
    with pytest.raises(ValueRangeError, match='temperature 256'):
        dji.encode_feedback(0, 0, 0, 256)


# --- collisions ---
def test_gm6020_id_n_collides_with_c620_id_n_plus_4():
    with pytest.raises(HardwareConfigError, match='yaw and wheel share command frame 0x1FF slot 0'):
        dji.check_collisions([('c620', 5), ('gm6020_voltage', 1)], names=['wheel', 'yaw'])


def test_gm6020_current_mode_id_n_collides_on_feedback_id():
    with pytest.raises(HardwareConfigError, match='share feedback id 0x205'):
        dji.check_collisions([('c620', 5), ('gm6020_current', 1)])


def test_distinct_motors_do_not_collide():
    dji.check_collisions(
        [
            ('c620', 1),
            ('c620', 2),
            ('c610', 3),
            ('c620', 4),
            ('gm6020_voltage', 5),
            ('gm6020_voltage', 6),
        ]
    )


# --- round trips ---
int16 = st.integers(-32768, 32767)


@given(st.lists(int16, min_size=0, max_size=4))
def test_command_round_trip(raws):
    assert list(dji.unpack_command(dji.pack_command(raws))) == raws + [0] * (4 - len(raws))


@given(st.integers(0, 8191), int16, int16, st.none() | st.integers(0, 255))
def test_feedback_round_trip(angle, rpm, current, temperature):
    data = dji.encode_feedback(angle, rpm, current, temperature)
    fb = dji.decode_feedback(data, has_temperature=temperature is not None)
    assert fb == (angle, rpm, current, temperature)


@given(st.sampled_from(list(DjiKind)), st.floats(-100.0, 100.0))
def test_si_round_trip_within_half_a_raw_step(kind, value):
    spec = dji.make_dji_spec(kind)
    raw = spec.raw_from_si(value)
    assert abs(raw) <= spec.raw_limit
    limit_si = spec.raw_limit * spec.si_per_raw
    expected = max(-limit_si, min(limit_si, value))
    assert spec.si_from_raw(raw) == pytest.approx(expected, abs=spec.si_per_raw / 2 + 1e-12)


@given(st.floats(-1e4, 1e4))
def test_ticks_from_rad_wraps_into_one_revolution(angle):
    ticks = dji.ticks_from_rad(angle)
    assert 0 <= ticks < 8192
    # the wrapped angle differs from the input by whole turns (within one tick)
    diff = angle - ticks * dji.RAD_PER_TICK
    turns = round(diff / (2 * math.pi))
    assert diff - turns * 2 * math.pi == pytest.approx(0.0, abs=dji.RAD_PER_TICK * 1.001)


def test_rpm_from_rad_per_s_saturates():
    assert dji.rpm_from_rad_per_s(2 * math.pi) == 60
    assert dji.rpm_from_rad_per_s(1e9) == 32767
    with pytest.raises(ValueRangeError, match='not finite'):
        dji.rpm_from_rad_per_s(math.nan)
