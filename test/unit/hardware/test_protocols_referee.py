"""Referee protocol: the CRCs, frames, the parser and the records, against docs/PROTOCOLS.md §6.

The F*/V1 vectors are the constructed frames of the protocol notes (checked there with DJI's
C CRC code and the team structs); the expected values are the ones they were built from.
"""

import itertools
import math
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.hardware.errors import ChecksumError, FrameLengthError, ValueRangeError
from rm_base.hardware.protocols import referee as ref
from rm_base.hardware.protocols.referee import ProtocolVersion as V


def frame(text: str) -> bytes:
    return bytes.fromhex(text)


F1 = frame('A5 0B 00 01 5C 01 00 41 2B 01 00 F1 53 65 00 00 00 00 85 6C')
F2 = frame('A5 0D 00 02 6F 01 02 03 02 B4 00 C8 00 28 00 F0 00 3C 00 07 7A FC')
F3 = frame('A5 11 00 03 C0 01 02 67 01 96 00 96 00 28 00 C8 00 3C 00 00 00 C8 41 03 84 FF')
F4 = frame('A5 10 00 04 E8 02 02 C0 5D C4 09 00 00 70 42 39 00 78 00 00 00 00 00 11 DC')
F5 = frame('A5 0E 00 05 08 02 02 00 00 00 00 00 00 00 00 3C 00 82 00 00 00 14 3F')
F6 = frame('A5 0C 00 06 A5 04 03 64 00 CE FF 00 00 01 00 91 00 00 00 97 DE')
F7 = frame(
    'A5 15 00 07 3F 01 03 01 01 03 00 03 01 41 42 31 41 08 00 00 03 00 8F 43 00 20 92 43 D2 97'
)
F8 = frame('A5 07 00 08 7B 07 02 01 01 0A 00 00 C4 41 0E A5')
V1 = frame('A9 53 94 06 20 AF D8 A2 60 19 F9 FF 0F 00 00 00 01 20 02 DE 1C')
REFEREE_FRAMES = (F1, F2, F3, F4, F5, F6, F7, F8)


def test_crcs_give_the_catalogue_check_values():
    assert ref.crc8(b'123456789') == 0x0B  # init 0xFF (0xA1 would be CRC-8/MAXIM, init 0)
    assert ref.crc16(b'123456789') == 0x6F91  # CRC-16/MCRF4XX
    assert ref.crc8(bytes.fromhex('A5 0D 00 00')) == 0xD3


@pytest.mark.parametrize(
    ('raw', 'version', 'expected'),
    [
        (F1, V.V2024, ref.GameStatus(1, ref.GameProgress.IN_MATCH, 299, 1_700_000_000)),
        (F2, V.V2024, ref.RobotStatus(3, 2, 180, 200, 40, 240, 60.0, True, True, True)),
        (F2, V.V2026, ref.RobotStatus(3, 2, 180, 200, 40, 240, 60.0, True, True, True)),
        # 2026 V2.0.0: a float speed limit before the output byte (gimbal and chassis on)
        (F3, V.V2026, ref.RobotStatus(103, 1, 150, 150, 40, 200, 60.0, True, True, False, 25.0)),
        # 2024: 24000 mV, 2500 mA, 60 W, buffer 57 J, heats 120 / 0 / 0
        (F4, V.V2024, ref.PowerHeat(57.0, 120, 0, 0, 24.0, 2.5, 60.0)),
        # the same bytes in 2025: the electrics are reserved, the rest is where it was
        (F4, V.V2025, ref.PowerHeat(57.0, 120, 0, 0)),
        (F5, V.V2026, ref.PowerHeat(60.0, 130, 0)),
        # mouse (100, -50, 0), left pressed, W + SHIFT + E
        (F6, V.V2025, ref.KeyboardMouse(100, -50, 0, True, False, 0x0091)),
        (F8, V.V2026, ref.ShootData(1, 1, 10, 24.5)),
    ],
)
def test_status_frames_decode_to_their_records(raw, version, expected):
    decoder = ref.StatusDecoder(version)
    assert decoder.decode(ref.decode_frame(raw)) == expected
    assert sum(decoder.decoded.values()) == 1


@pytest.mark.parametrize(
    ('raw', 'version'),
    [(F3, V.V2024), (F3, V.V2025), (F4, V.V2026), (F5, V.V2024), (F5, V.V2025)],
)
def test_a_length_the_version_does_not_have_is_dropped_and_counted(raw, version):
    decoder = ref.StatusDecoder(version)
    parsed = ref.decode_frame(raw)
    assert decoder.decode(parsed) is None
    assert decoder.wrong_length == {(parsed.cmd_id, len(parsed.data)): 1}


def test_commands_the_robot_does_not_read_are_ignored_and_counted():
    decoder = ref.StatusDecoder(V.V2026)
    assert decoder.decode(ref.RawFrame(0x0105, bytes(3))) is None
    assert decoder.ignored == {0x0105: 1}


def test_projectile_allowance_has_a_fortress_share_from_2025_on():
    decoder = ref.StatusDecoder(V.V2025)
    assert decoder.decode(ref.RawFrame(0x0208, bytes((100, 0, 5, 0, 200, 1)))) == (
        ref.ProjectileAllowance(100, 5, 456)
    )
    assert decoder.decode(ref.RawFrame(0x0208, bytes((1, 0, 2, 0, 3, 0, 4, 0)))) == (
        ref.ProjectileAllowance(1, 2, 3, 4)
    )


def test_hurt_and_position_decode():
    decoder = ref.StatusDecoder(V.V2024)
    assert decoder.decode(ref.RawFrame(0x0206, bytes((0x52,)))) == ref.Hurt(armor_id=2, cause=5)
    position = decoder.decode(ref.RawFrame(0x0203, struct.pack('<fff', 1.5, 2.0, 90.0)))
    assert (position.x_m, position.y_m) == (1.5, 2.0)
    assert position.heading_rad == pytest.approx(math.pi / 2)


@pytest.mark.parametrize('raw', REFEREE_FRAMES)
def test_frames_encode_back_to_the_same_bytes(raw):
    parsed = ref.decode_frame(raw)
    assert ref.encode_frame(parsed.cmd_id, parsed.data, parsed.seq) == raw


def test_a_client_line_encodes_to_the_reference_frame():
    # sender 3 -> client 0x0103, "AB1": add a green line on layer 1, width 3, (960,540)->(1160,540)
    figure = ref.line(b'AB1', (960, 540), (1160, 540), layer=1, color=ref.Color.GREEN, width=3)
    assert ref.encode_frame(0x0301, ref.draw(3, [figure]), seq=7) == F7


def test_drawing_three_figures_uses_the_five_figure_command_padded_with_no_ops():
    figures = [ref.circle(b'CR%d' % i, (100 * i, 100), 10 + i) for i in range(3)]
    data = ref.draw(103, figures)
    assert data[:6] == bytes.fromhex('0301 6700 6701')  # 0x0103, blue 3 (103) -> client 0x0167
    assert len(data) == 6 + 5 * 15
    assert data[6 + 3 * 15 :] == bytes(2 * 15)


def test_a_float_figure_carries_the_value_times_1000_in_its_last_word():
    data = ref.encode_figure(ref.number(b'PWR', (50, 900), -12.345))
    assert int.from_bytes(data[11:15], 'little', signed=True) == -12345


@pytest.mark.parametrize(
    ('figure', 'match'),
    [
        (ref.line(b'AB', (0, 0), (1, 1)), 'name must be 3 bytes'),
        (ref.line(b'ABC', (2048, 0), (1, 1)), 'x 2048 does not fit 11 bits'),
        (ref.line(b'ABC', (0, 0), (1, 1), layer=10), 'layer must be 0..9'),
    ],
)
def test_a_figure_that_does_not_fit_is_refused(figure, match):
    with pytest.raises(ValueRangeError, match=match):
        ref.encode_figure(figure)


def test_interaction_content_is_limited_and_delete_names_a_layer():
    with pytest.raises(ValueRangeError, match='113 bytes > 112'):
        ref.interaction(0x0200, 3, 4, bytes(113))
    with pytest.raises(ValueRangeError, match='1 to 7 figures'):
        ref.draw(3, [])
    assert ref.delete(3, ref.DeleteOp.LAYER, 2) == bytes.fromhex('0001 0300 0301 01 02')


def test_the_image_link_remote_frame_decodes():
    (raw,) = ref.FrameParser(image_link=True).feed(V1)
    assert raw.cmd_id == ref.REMOTE_FRAME_ID
    remote = ref.StatusDecoder(V.V2026).decode(raw)
    # ch 1684, 1024, 700, 364; mode S; custom-left; dial 1200; trigger; mouse (-7, 15, 0)
    assert (remote.right_x, remote.right_y, remote.left_y, remote.left_x) == (660, 0, -324, -660)
    assert remote.mode is ref.ModeSwitch.S
    assert (remote.pause, remote.custom_left, remote.custom_right) == (False, True, False)
    assert (remote.dial, remote.trigger) == (176, True)
    assert (remote.mouse_x, remote.mouse_y, remote.mouse_wheel) == (-7, 15, 0)
    assert (remote.mouse_left, remote.mouse_right, remote.mouse_middle) == (True, False, False)
    assert remote.keys == 0x0220  # CTRL + F


def test_a_remote_frame_with_a_stick_out_of_range_is_rejected_and_counted():
    payload = bytearray(V1[2:19])
    payload[0:2] = (0x7FF & 0xFF, payload[1] | 0x07)  # ch0 = 2047
    decoder = ref.StatusDecoder(V.V2026)
    assert decoder.decode(ref.RawFrame(ref.REMOTE_FRAME_ID, bytes(payload))) is None
    assert decoder.rejected == {ref.REMOTE_FRAME_ID: 1}


def test_decode_frame_refuses_damaged_and_partial_frames():
    with pytest.raises(ChecksumError, match='CRC16'):
        ref.decode_frame(F2[:-1] + bytes((F2[-1] ^ 1,)))
    with pytest.raises(ChecksumError, match='CRC8'):
        ref.decode_frame(F2[:4] + bytes((F2[4] ^ 1,)) + F2[5:])
    with pytest.raises(FrameLengthError):
        ref.decode_frame(F2[:-3])


def test_every_single_bit_flip_of_a_frame_is_rejected():
    for bit in range(len(F2) * 8):
        damaged = bytearray(F2)
        damaged[bit // 8] ^= 1 << bit % 8
        parser = ref.FrameParser()
        assert parser.feed(bytes(damaged)) == [], f'bit {bit}'


STREAM = b'\x00\xa5\x13' + b''.join(f + b'\xa5\xa9' for f in REFEREE_FRAMES) + V1 + F1


@given(cuts=st.lists(st.integers(0, len(STREAM)), max_size=12))
def test_any_split_of_the_stream_gives_the_same_frames(cuts):
    parser = ref.FrameParser(image_link=True)
    bounds = sorted({0, len(STREAM), *cuts})
    frames = []
    for start, end in itertools.pairwise(bounds):
        frames += parser.feed(STREAM[start:end])
    expected = [ref.decode_frame(f) for f in (*REFEREE_FRAMES, F1)]
    assert [f for f in frames if f.cmd_id != ref.REMOTE_FRAME_ID] == expected
    assert [f.data for f in frames if f.cmd_id == ref.REMOTE_FRAME_ID] == [V1[2:19]]


def test_a_frame_starting_inside_a_damaged_one_is_found():
    damaged = bytearray(F4)
    damaged[-1] ^= 0xFF  # its CRC16 fails
    inner = F1  # a whole frame inside the damaged one's data would be found on resync
    parser = ref.FrameParser()
    assert parser.feed(bytes(damaged[:10]) + inner + bytes(damaged[10:])) == [
        ref.decode_frame(inner)
    ]
    assert parser.stats.crc_errors + parser.stats.header_errors >= 1


@given(noise=st.binary(max_size=400), version=st.sampled_from(list(V)))
def test_noise_never_raises_and_every_frame_found_has_good_crcs(noise, version):
    parser = ref.FrameParser(image_link=True)
    decoder = ref.StatusDecoder(version)
    for found in parser.feed(noise):
        decoder.decode(found)  # never raises: a bad layout is counted, not decoded
        if found.cmd_id != ref.REMOTE_FRAME_ID:
            again = ref.encode_frame(found.cmd_id, found.data, found.seq)
            assert ref.decode_frame(again) == found


@given(
    cmd=st.sampled_from([*list(ref.Cmd), ref.REMOTE_FRAME_ID, 0x0105]),
    data=st.binary(max_size=40),
    version=st.sampled_from(list(V)),
)
def test_any_command_and_length_decodes_or_is_counted(cmd, data, version):
    decoder = ref.StatusDecoder(version)
    decoder.decode(ref.RawFrame(cmd, data))
    counted = (
        sum(decoder.decoded.values()) + sum(decoder.wrong_length.values())
        + sum(decoder.ignored.values()) + sum(decoder.rejected.values())
    )
    assert counted == 1


# -- encoding: the referee's side (the simulated referee sends these) --------------------------


@pytest.mark.parametrize(
    ('raw', 'version'),
    [(F1, V.V2024), (F2, V.V2024), (F2, V.V2026), (F3, V.V2026), (F4, V.V2024), (F5, V.V2026),
     (F6, V.V2025), (F8, V.V2026)],
)
def test_a_decoded_vector_encodes_back_to_its_own_bytes(raw, version):
    parsed = ref.decode_frame(raw)
    record = ref.StatusDecoder(version).decode(parsed)
    assert ref.encode_frame(*ref.encode_status(record, version), seq=parsed.seq) == raw


@pytest.mark.parametrize('version', list(V))
@pytest.mark.parametrize(
    'record',
    [
        ref.GameStatus(4, ref.GameProgress.COUNTDOWN, 5, 1_800_000_000),
        ref.RobotStatus(103, 3, 0, 400, 40, 100, 45.0, False, True, False),
        ref.PowerHeat(12.0, 95, 200),
        ref.RobotPosition(1.5, -2.25, math.radians(90.0)),
        ref.Hurt(3, 0),
        ref.ShootData(2, 1, 2, 15.5),
        ref.ProjectileAllowance(200, 10, 350, 0),
        ref.KeyboardMouse(-3, 7, 1, False, True, 0x8001),
    ],
)
def test_every_record_round_trips_in_every_version(record, version):
    cmd_id, data = ref.encode_status(record, version)
    decoded = ref.StatusDecoder(version).decode(ref.RawFrame(cmd_id, data))
    if isinstance(record, ref.PowerHeat) and version is V.V2025:
        record = ref.PowerHeat(12.0, 95, 200, 0)  # the second 17 mm heat is sent as 0
    if isinstance(record, ref.PowerHeat) and version is V.V2024:  # and the electrics as 0
        record = ref.PowerHeat(12.0, 95, 200, 0, 0.0, 0.0, 0.0)
    if isinstance(record, ref.ProjectileAllowance) and version is V.V2024:
        record = ref.ProjectileAllowance(200, 10, 350)  # no fortress field before 2025
    if isinstance(record, ref.RobotPosition):
        assert decoded.heading_rad == pytest.approx(record.heading_rad)
        record = ref.RobotPosition(record.x_m, record.y_m, decoded.heading_rad)
    assert decoded == record


def test_a_record_the_version_cannot_carry_is_refused():
    with pytest.raises(ValueError, match='only sent in 2026'):
        ref.encode_status(ref.RobotStatus(3, 1, 1, 1, 1, 1, 1.0, True, True, True, 25.0), V.V2024)
    with pytest.raises(ValueError):  # 70000 does not fit the u16 heat field
        ref.encode_status(ref.PowerHeat(1.0, 70000, 0), V.V2026)
    with pytest.raises(TypeError, match='not a referee status record'):
        ref.encode_status(object(), V.V2026)


def test_a_text_figure_carries_its_characters_in_30_bytes():
    figure = ref.text_figure(b'MOD', (100, 800), 4, font_size=24, layer=2)
    data = ref.draw_text(3, figure, 'GYRO')
    assert data[:6] == bytes.fromhex('1001 0300 0301')  # 0x0110, sender 3 -> client 0x0103
    assert len(data) == 6 + 15 + 30 and data[-30:] == b'GYRO' + bytes(26)
    parsed = ref.decode_interaction(data)
    assert ref.decode_drawing(parsed.content_id, parsed.content) == ([figure], 'GYRO')
    with pytest.raises(ValueRangeError, match='> 30'):
        ref.draw_text(3, figure, 'X' * 31)
    with pytest.raises(ValueRangeError, match='not a TEXT'):
        ref.draw_text(3, ref.line(b'ABC', (0, 0), (1, 1)), 'A')


def test_the_reference_line_decodes_back_to_its_figure_and_padding_is_left_out():
    figure = ref.line(b'AB1', (960, 540), (1160, 540), layer=1, color=ref.Color.GREEN, width=3)
    parsed = ref.decode_interaction(ref.decode_frame(F7).data)
    assert (parsed.content_id, parsed.sender_id, parsed.receiver_id) == (0x0101, 3, 0x0103)
    assert ref.decode_drawing(parsed.content_id, parsed.content) == ([figure], None)
    three = [ref.circle(b'CR%d' % i, (100 * i, 100), 10 + i) for i in range(3)]
    parsed = ref.decode_interaction(ref.draw(103, three))
    assert ref.decode_drawing(parsed.content_id, parsed.content) == (three, None)
    number = ref.number(b'PWR', (50, 900), 12.345, op=ref.FigureOp.MODIFY)
    assert ref.decode_figure(ref.encode_figure(number)) == number


@pytest.mark.parametrize(('content_id', 'content', 'match'), [
    (0x0102, bytes(15), '0x0102 content of 15 bytes'),
    (0x0200, bytes(15), 'not a drawing command'),
    (0x0110, bytes(40), '0x0110 content of 40 bytes'),
])
def test_a_drawing_of_the_wrong_shape_is_refused(content_id, content, match):
    with pytest.raises(ValueRangeError, match=match):
        ref.decode_drawing(content_id, content)
