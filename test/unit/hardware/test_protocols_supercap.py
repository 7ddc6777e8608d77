"""The supercap controller's frames (HKUST RM2024): docs/PROTOCOLS.md §8's vectors."""

import math
import struct

import pytest
from rm_base.hardware.errors import FrameLengthError, ValueRangeError
from rm_base.hardware.protocols import supercap as cap


@pytest.mark.parametrize(('args', 'hex_'), [
    ((80.0, 60.0), '01 50 00 3C 00 00 00 00'),  # the fact sheet's: enable, 80 W, 60 J
    ((80.4, 59.6), '01 50 00 3C 00 00 00 00'),  # whole numbers
    ((10.0, -5.0), '01 1E 00 00 00 00 00 00'),  # the board's floor, no negative buffer
    ((400.0, 999.0), '01 FA 00 2C 01 00 00 00'),  # never above 250 W (output off), 300 J
])
def test_the_command_is_the_boards_bytes(args, hex_):
    assert cap.encode_command(*args) == bytes.fromhex(hex_)


def test_the_flags_and_a_command_read_back_as_the_board_reads_it():
    data = cap.encode_command(120.0, 40.0, enable=False, restart=True)
    assert data[0] == 0x02
    assert cap.decode_command(data) == (False, True, 120, 40)


@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_a_non_finite_limit_or_buffer_is_refused(bad):
    with pytest.raises(ValueRangeError):
        cap.encode_command(bad, 60.0)
    with pytest.raises(ValueRangeError):
        cap.encode_command(80.0, bad)


def test_the_feedback_vector_decodes_to_power_limit_and_energy():
    fb = cap.decode_feedback(bytes.fromhex('00 00 00 36 42 50 00 7F'))
    assert fb == cap.CapFeedback(cap.CapError(0), 45.5, 80, 127 / 255)
    assert cap.encode_feedback(0, 45.5, 80, 127 / 255) == bytes.fromhex('00 00 00 36 42 50 00 7F')


def test_the_error_bits_name_what_is_wrong():
    fb = cap.decode_feedback(bytes.fromhex('81 00 00 00 00 50 00 00'))
    assert fb.errors == cap.CapError.UNDER_VOLTAGE | cap.CapError.OUTPUT_DISABLED
    assert fb.energy == 0.0


@pytest.mark.parametrize('data', [b'', bytes(7), bytes(9)])
def test_a_frame_of_another_length_is_refused(data):
    with pytest.raises(FrameLengthError):
        cap.decode_feedback(data)
    with pytest.raises(FrameLengthError):
        cap.decode_command(data)


def test_a_nan_power_is_refused():
    with pytest.raises(ValueRangeError):
        cap.decode_feedback(struct.pack('<BfHB', 0, math.nan, 80, 10))


@pytest.mark.parametrize('energy', [-0.01, 1.01, math.nan])
def test_the_simulated_feedback_refuses_an_energy_outside_0_to_1(energy):
    with pytest.raises(ValueRangeError):
        cap.encode_feedback(0, 10.0, 80, energy)
