"""HiPNUC IMU frames: vectors H0–H3, 0x91 and legacy encode/decode, streaming parser."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.hardware.errors import ChecksumError, FrameLengthError, ProtocolError, ValueRangeError
from rm_base.hardware.protocols import hipnuc

H1 = bytes.fromhex(
    '5A A5 4C 00 14 BB 91 08 15 23 09 A2 C4 47 08 15 1C 00 CC E8 61 BE 9A 35 56 3E 65 EA 72 3F'
    ' 31 D0 7C BD 75 DD C5 BB 6B D7 24 BC 89 88 FC 40 01 00 6A 41 AB 2A 70 C2 96 D4 50 41 ED 03'
    ' 43 41 41 F4 F4 C2 CC CA F8 BE 73 6A 19 BE F0 00 1C 3D 8D 37 5C 3F'
)
H2 = bytes.fromhex(
    '5A A5 4C 00 06 EE 91 00 00 19 80 E6 C5 47 E8 03 00 00 00 00 00 00 00 00 00 00 00 00 80 3F'
    ' 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00'
    ' 00 00 00 00 B4 42 F3 04 35 3F 00 00 00 00 00 00 00 00 F3 04 35 3F'
)
H3 = bytes.fromhex(
    '5A A5 15 00 23 08 A0 E8 03 18 FC 00 00 B0 64 00 9C FF 00 00 D0 E8 03 18 FC 84 03'
)
D2R = math.pi / 180


def test_h0_crc16_xmodem_check_value():
    assert hipnuc.crc16_xmodem(b'123456789') == 0x31C3


def test_h1_official_example_frame():
    assert hipnuc.frame_crc(H1) == 0xBB14
    s = hipnuc.decode_payload(hipnuc.decode_frame(H1))
    assert (s.status, s.temperature, s.system_time_ms) == (0x1508, 35, 1840392)
    assert s.pressure == pytest.approx(100676.07, abs=0.01)
    # acc in g * 9.80665
    assert s.acc == pytest.approx((-2.1635, 2.0514, 9.3054), abs=1e-4)
    assert s.gyr == pytest.approx(tuple(d * D2R for d in (-0.06172, -0.00604, -0.01006)), abs=1e-6)
    assert s.mag == pytest.approx((7.8917, 14.6250, -60.0417), abs=1e-4)
    assert s.euler == pytest.approx(tuple(d * D2R for d in (13.0519, 12.1885, -122.4771)), abs=1e-6)
    assert s.quat == pytest.approx((-0.48592, -0.14982, 0.03809, 0.86022), abs=1e-5)
    assert math.fsum(q * q for q in s.quat) == pytest.approx(1.0, abs=1e-4)


def test_h2_synthetic_frame_encodes_byte_for_byte():
    payload = hipnuc.encode_imusol(
        acc=(0.0, 0.0, hipnuc.STANDARD_GRAVITY),
        gyr=(0.0, 0.0, 0.0),
        mag=(0.0, 0.0, 0.0),
        euler=(0.0, 0.0, math.pi / 2),
        quat=(math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)),
        temperature=25,
        pressure=101325.0,
        system_time_ms=1000,
        status=0,
    )
    frame = hipnuc.encode_frame(payload)
    assert frame == H2
    assert frame[4:6] == (0xEE06).to_bytes(2, 'little')
    s = hipnuc.decode_payload(hipnuc.decode_frame(H2))
    assert s.acc == pytest.approx((0.0, 0.0, 9.80665))
    assert s.euler[2] == pytest.approx(math.pi / 2)


def test_h2_one_flipped_payload_bit_fails_the_crc():
    bad = bytearray(H2)
    bad[20] ^= 0x01
    with pytest.raises(ChecksumError, match='CRC 0xEE06 in frame'):
        hipnuc.decode_frame(bad)


def test_h3_legacy_items():
    s = hipnuc.decode_payload(hipnuc.decode_frame(H3))
    # acc 1000/1000 g, gyr 100/10 deg/s, pitch 1000/100, roll -1000/100, yaw 900/10 deg
    g = hipnuc.STANDARD_GRAVITY
    assert s.acc == pytest.approx((g, -g, 0.0))
    assert s.gyr == pytest.approx((10 * D2R, -10 * D2R, 0.0))
    assert s.euler == pytest.approx((-10 * D2R, 10 * D2R, 90 * D2R))  # (roll, pitch, yaw)
    assert s.quat is None
    payload = hipnuc.encode_legacy(
        acc=(g, -g, 0.0), gyr=(10 * D2R, -10 * D2R, 0.0), euler=(-10 * D2R, 10 * D2R, 90 * D2R)
    )
    assert hipnuc.encode_frame(payload) == H3


def test_legacy_quat_pressure_mag_and_user_id():
    payload = hipnuc.encode_legacy(
        user_id=7, mag=(1.5, -2.0, 30.0), quat=(1.0, 0.0, 0.0, 0.0), pressure=90000.0
    )
    s = hipnuc.decode_payload(payload)
    assert (s.user_id, s.mag, s.quat, s.pressure) == (
        7,
        (1.5, -2.0, 30.0),
        (1.0, 0.0, 0.0, 0.0),
        90000.0,
    )


def test_inssol_item_is_skipped_not_decoded():
    payload = bytes((hipnuc.TAG_INSSOL,)) + bytes(103) + hipnuc.encode_legacy(user_id=1)
    s = hipnuc.decode_payload(payload)
    assert s.skipped_tags == (0x81,)
    assert s.user_id == 1


def test_an_item_of_unknown_length_ends_the_payload_and_keeps_what_came_before():
    # 0x91 then 0x83 (float INS, layout unknown here): the 0x91 is read, 0x83 is named.
    payload = H2[hipnuc.HEADER_LENGTH:] + b'\x83' + bytes(40) + hipnuc.encode_legacy(user_id=9)
    s = hipnuc.decode_payload(payload)
    assert s.acc == pytest.approx((0.0, 0.0, 9.80665), abs=1e-5)
    assert s.unread_tag == 0x83
    assert s.user_id is None  # after the unknown item: not read
    assert hipnuc.decode_payload(H2[hipnuc.HEADER_LENGTH:]).unread_tag is None
    p = hipnuc.HipnucParser()
    assert [x.unread_tag for x in p.feed(hipnuc.encode_frame(payload))] == [0x83]
    assert (p.frames_ok, p.decode_errors) == (1, 0)


@pytest.mark.parametrize(
    ('frame', 'error', 'match'),
    [
        (b'\x5a\xa5\x01', FrameLengthError, 'shorter than its header'),
        (b'\x5a\xa6\x01\x00\x00\x00\x90', ProtocolError, 'expected 5a a5'),
        (b'\x5a\xa5\x05\x00\x00\x00\x90', FrameLengthError, 'LEN 5 does not match'),
    ],
)
def test_malformed_frames(frame, error, match):
    with pytest.raises(error, match=match):
        hipnuc.decode_frame(frame)


def test_malformed_payloads():
    with pytest.raises(ProtocolError, match='unknown HiPNUC item tag 0x42 at payload offset 0'):
        hipnuc.decode_payload(b'\x42\x00')
    with pytest.raises(FrameLengthError, match='needs 76 bytes, 10 left'):
        hipnuc.decode_payload(b'\x91' + bytes(9))
    with pytest.raises(FrameLengthError, match='payload length 0'):
        hipnuc.encode_frame(b'')
    with pytest.raises(FrameLengthError, match='payload length 507'):
        hipnuc.encode_frame(bytes(507))


def test_encoders_reject_bad_values():
    with pytest.raises(ValueRangeError, match='acc must be 3 finite'):
        hipnuc.encode_legacy(acc=(math.nan, 0.0, 0.0))
    with pytest.raises(ValueRangeError, match='does not fit int16'):
        hipnuc.encode_legacy(gyr=(100.0, 0.0, 0.0))  # 100 rad/s = 57296 * 0.1 deg/s
    with pytest.raises(ValueRangeError, match='at least one item'):
        hipnuc.encode_legacy()
    with pytest.raises(ValueRangeError, match='out of range'):
        hipnuc.encode_imusol(
            acc=(0, 0, 0),
            gyr=(0, 0, 0),
            mag=(0, 0, 0),
            euler=(0, 0, 0),
            quat=(1, 0, 0, 0),
            temperature=200,
        )


# --- streaming parser ---
def test_parser_finds_frames_in_garbage_and_split_reads():
    p = hipnuc.HipnucParser()
    stream = b'\x00\x5a\x11' + H1 + b'\xff\x5a' + H3 + H2
    out = []
    for i in range(0, len(stream), 5):  # 5-byte reads split every frame
        out += p.feed(stream[i : i + 5])
    assert len(out) == 3
    assert out[1].acc[0] == pytest.approx(hipnuc.STANDARD_GRAVITY)
    assert p.frames_ok == 3
    assert p.bytes_discarded == 5  # 00 5A 11 before H1, FF 5A before H3
    assert p.crc_errors == 0


def test_parser_counts_crc_failures_and_recovers():
    bad = bytearray(H2)
    bad[30] ^= 0x40
    p = hipnuc.HipnucParser()
    out = p.feed(bytes(bad) + H3)
    assert len(out) == 1
    assert p.crc_errors == 1
    assert p.bytes_discarded == len(H2)


def test_parser_finds_a_frame_hidden_inside_a_false_header():
    # a fake header announcing 40 payload bytes, immediately followed by a real frame
    p = hipnuc.HipnucParser()
    out = p.feed(b'\x5a\xa5\x28\x00\x00\x00' + H3 + bytes(40))
    assert len(out) == 1
    assert p.crc_errors == 1


def test_parser_counts_bad_lengths_and_undecodable_payloads():
    p = hipnuc.HipnucParser()
    unknown = hipnuc.encode_frame(b'\x42\x00')
    assert p.feed(b'\x5a\xa5\xff\xff' + unknown + H3) != []
    assert p.length_errors == 1
    assert p.decode_errors == 1
    assert 'unknown HiPNUC item tag' in p.last_error


def test_parser_keeps_a_trailing_half_sync():
    p = hipnuc.HipnucParser()
    assert p.feed(b'\x01\x02' + H3[:1]) == []
    assert len(p.feed(H3[1:])) == 1
    assert p.bytes_discarded == 2


f32 = st.floats(-1e3, 1e3, allow_nan=False, width=32)


@given(
    st.tuples(f32, f32, f32),
    st.tuples(f32, f32, f32),
    st.tuples(f32, f32, f32),
    st.tuples(f32, f32, f32),
    st.tuples(f32, f32, f32, f32),
    st.integers(-128, 127),
    st.integers(0, 2**32 - 1),
    st.integers(0, 0xFFFF),
)
def test_imusol_round_trip(acc, gyr, mag, euler, quat, temp, t_ms, status):
    frame = hipnuc.encode_frame(
        hipnuc.encode_imusol(
            acc=acc,
            gyr=gyr,
            mag=mag,
            euler=euler,
            quat=quat,
            temperature=temp,
            system_time_ms=t_ms,
            status=status,
        )
    )
    (s,) = hipnuc.HipnucParser().feed(frame)
    assert (s.temperature, s.system_time_ms, s.status, s.quat, s.mag) == (
        temp,
        t_ms,
        status,
        quat,
        mag,
    )
    for got, want in ((s.acc, acc), (s.gyr, gyr), (s.euler, euler)):
        assert got == pytest.approx(want, rel=1e-6, abs=1e-4)


@given(
    st.tuples(*[st.integers(-32768, 32767)] * 3),
    st.tuples(*[st.integers(-32768, 32767)] * 3),
    st.tuples(*[st.integers(-32768, 32767)] * 3),
)
def test_legacy_round_trip_on_the_integer_grid(a, g, e):
    payload = (
        b'\xa0'
        + b''.join(v.to_bytes(2, 'little', signed=True) for v in a)
        + b'\xb0'
        + b''.join(v.to_bytes(2, 'little', signed=True) for v in g)
        + b'\xd0'
        + b''.join(v.to_bytes(2, 'little', signed=True) for v in e)
    )
    s = hipnuc.decode_payload(payload)
    assert hipnuc.encode_legacy(acc=s.acc, gyr=s.gyr, euler=s.euler) == payload


@given(st.binary(max_size=600))
def test_parser_never_raises_on_garbage(data):
    p = hipnuc.HipnucParser()
    p.feed(data)
    assert p.bytes_discarded <= len(data)
