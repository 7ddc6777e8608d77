"""DJI DR16 DBUS frames: vectors B1–B3, range checks, round trip."""

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.hardware.errors import FrameLengthError, ValueRangeError
from rm_base.hardware.protocols import dbus
from rm_base.hardware.protocols.dbus import DbusFrame, Key, Switch


def h(text):
    return bytes.fromhex(text)


@pytest.mark.parametrize(
    ('name', 'frame', 'data'),
    [
        ('B1', DbusFrame(), '00 04 20 00 01 F8 00 00 00 00 00 00 00 00 00 00 00 04'),
        # ch 1684-1024=660, 364-1024=-660, 0, 1200-1024=176; wheel 1684 -> 660
        (
            'B2',
            DbusFrame(
                (660, -660, 0, 176),
                Switch.UP,
                Switch.DOWN,
                (100, -50, 0),
                True,
                False,
                Key.W | Key.SHIFT,
                660,
            ),
            '94 66 0B 00 61 99 64 00 CE FF 00 00 01 00 11 00 94 06',
        ),
        (
            'B3',
            DbusFrame(
                (-660, 660, -660, 660),
                Switch.DOWN,
                Switch.UP,
                (-1, 0, -1),
                False,
                True,
                Key.B,
                -660,
            ),
            '6C A1 34 5B 28 6D FF FF 00 00 FF FF 00 01 00 80 6C 01',
        ),
    ],
)
def test_dbus_vectors(name, frame, data):
    assert dbus.encode(frame) == h(data), name
    assert dbus.decode(h(data)) == frame


@pytest.mark.parametrize('n', [0, 17, 19])
def test_when_length_wrong_expect_error(n):
    with pytest.raises(FrameLengthError, match=f'18 bytes, got {n}'):
        dbus.decode(bytes(n))


def test_when_channel_out_of_range_expect_rejection():
    # all-zero frame: channels read 0 raw -> -1024, beyond +-700
    with pytest.raises(ValueRangeError, match='channel 0 -1024 beyond ±700'):
        dbus.decode(bytes(18))


def with_channel_0(raw: int) -> bytes:
    """The centred vector with channel 0's 11 bits set to raw."""
    data = bytearray(h('00 04 20 00 01 F8 00 00 00 00 00 00 00 00 00 00 00 04'))
    data[0] = raw & 0xFF
    data[1] = (data[1] & 0xF8) | (raw >> 8)
    return bytes(data)


@pytest.mark.parametrize(('offset', 'reads'), [(661, 660), (700, 660), (-700, -660), (-1, -1)])
def test_a_stick_up_to_700_is_accepted_and_clamped_to_660_as_djis_decoder_does(offset, reads):
    assert dbus.decode(with_channel_0(1024 + offset)).channels[0] == reads


@pytest.mark.parametrize('offset', [701, -701])
def test_a_stick_beyond_700_rejects_the_frame(offset):
    with pytest.raises(ValueRangeError, match='beyond ±700'):
        dbus.decode(with_channel_0(1024 + offset))


def test_when_wheel_out_of_range_expect_rejection():
    data = bytearray(h('00 04 20 00 01 F8 00 00 00 00 00 00 00 00 00 00 00 04'))
    data[16:18] = (1680 + 50).to_bytes(2, 'little')
    with pytest.raises(ValueRangeError, match='wheel 706'):
        dbus.decode(bytes(data))
    data[16:18] = (1700).to_bytes(2, 'little')
    assert dbus.decode(bytes(data)).wheel == 660


def test_when_switch_reads_zero_expect_rejection():
    data = bytearray(h('00 04 20 00 01 F8 00 00 00 00 00 00 00 00 00 00 00 04'))
    data[5] &= 0x0F  # both switches 0
    with pytest.raises(ValueRangeError, match='switch value 0'):
        dbus.decode(bytes(data))


@pytest.mark.parametrize(
    ('frame', 'match'),
    [
        (DbusFrame(channels=(661, 0, 0, 0)), 'outside ±660'),
        (DbusFrame(wheel=-700), 'outside ±660'),
        (DbusFrame(switch_a=0), 'switch must be 1, 2 or 3'),
        (DbusFrame(keys=0x10000), 'outside uint16'),
        (DbusFrame(mouse=(40000, 0, 0)), 'does not fit int16'),
        (DbusFrame(channels=(0, 0, 0)), 'needs 4 channels'),
    ],
)
def test_encode_rejects_bad_fields(frame, match):
    with pytest.raises(ValueRangeError, match=match):
        dbus.encode(frame)


ch = st.integers(-660, 660)
i16 = st.integers(-32768, 32767)


@given(
    st.tuples(ch, ch, ch, ch),
    st.sampled_from(list(Switch)),
    st.sampled_from(list(Switch)),
    st.tuples(i16, i16, i16),
    st.booleans(),
    st.booleans(),
    st.integers(0, 0xFFFF),
    ch,
)
def test_round_trip(channels, sa, sb, mouse, left, right, keys, wheel):
    frame = DbusFrame(channels, sa, sb, mouse, left, right, keys, wheel)
    data = dbus.encode(frame)
    assert len(data) == 18
    assert dbus.decode(data) == frame


CENTRED = h('00 04 20 00 01 F8 00 00 00 00 00 00 00 00 00 00 00 04')


class Clock:
    def __init__(self) -> None:
        self.ns = 0

    def __call__(self) -> int:
        return self.ns


def test_the_stream_splits_frames_at_the_silences_between_them():
    clock = Clock()
    stream = dbus.DbusStream(clock)
    assert stream.feed(CENTRED[:5]) == []
    clock.ns += 1_000_000  # the rest of the burst, 1 ms later
    assert stream.feed(CENTRED[5:]) == [DbusFrame()]
    clock.ns += 14_000_000
    assert stream.feed(CENTRED + CENTRED) == [DbusFrame(), DbusFrame()]  # two, read late
    assert (stream.frames_ok, stream.length_errors, stream.bytes_discarded) == (3, 0, 0)


def test_a_frame_cut_short_by_a_silence_is_dropped_and_the_next_one_read_whole():
    clock = Clock()
    stream = dbus.DbusStream(clock)
    assert stream.feed(CENTRED[7:]) == []  # opened mid-frame: its last 11 bytes
    clock.ns += 12_000_000
    assert stream.feed(CENTRED) == [DbusFrame()]
    assert (stream.length_errors, stream.bytes_discarded) == (1, 11)


def test_an_invalid_frame_is_counted_and_dropped():
    stream = dbus.DbusStream(Clock())
    assert stream.feed(bytes(18)) == []
    assert (stream.decode_errors, stream.bytes_discarded, stream.frames_ok) == (1, 18, 0)

