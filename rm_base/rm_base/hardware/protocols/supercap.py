"""The super-capacitor controller's CAN protocol (HKUST ENTERPRIZE RM2024): bytes <-> values.

docs/PROTOCOLS.md §8. The robot sends the referee's chassis power limit and buffer energy
on 0x061; the controller answers on 0x051 every millisecond with its error bits, the
chassis power it measures, the limit it works to and how full the capacitor is. Both
frames are 8 bytes, little endian (the board copies its structs byte for byte).
"""

from __future__ import annotations

import enum
import math
import struct
from typing import NamedTuple

from rm_base.hardware.errors import FrameLengthError, ValueRangeError

COMMAND_ID = 0x061
FEEDBACK_ID = 0x051
FRAME_LENGTH = 8
#: The board clamps the limit to this range; above MAX_LIMIT_W it switches its output off,
#: so the robot never sends more.
MIN_LIMIT_W, MAX_LIMIT_W = 30, 250
MAX_BUFFER_J = 300

_COMMAND = struct.Struct('<BHH3x')  # flags, limit [W], buffer [J]
_FEEDBACK = struct.Struct('<BfHB')  # error bits, chassis power [W], limit [W], energy/255


class CapError(enum.IntFlag):
    """Byte 0 of the feedback: what the controller reports wrong."""

    UNDER_VOLTAGE = 0x01
    OVER_VOLTAGE = 0x02
    BUCK_BOOST = 0x04
    SHORT_CIRCUIT = 0x08
    OVER_TEMPERATURE = 0x10
    NO_INPUT = 0x20
    CAPACITOR = 0x40
    OUTPUT_DISABLED = 0x80


class CapFeedback(NamedTuple):
    """One 0x051 frame.

    Attributes:
        errors: the error bits (0: none).
        chassis_power_w: the chassis' power the controller measures [W].
        limit_w: the power limit it works to [W].
        energy: how full the capacitor is, 0..1 (in steps of 1/255).
    """

    errors: CapError
    chassis_power_w: float
    limit_w: int
    energy: float


def encode_command(limit_w: float, buffer_j: float, *, enable: bool = True,
                   restart: bool = False) -> bytes:
    """The 0x061 frame: the referee's limit [W] and buffer energy [J], whole numbers.

    The limit goes out within [MIN_LIMIT_W, MAX_LIMIT_W] (the board's own range; more
    would switch its output off), the buffer within [0, MAX_BUFFER_J].

    Raises:
        ValueRangeError: a NaN or infinite value.
    """
    if not (math.isfinite(limit_w) and math.isfinite(buffer_j)):
        raise ValueRangeError(f'supercap command: limit {limit_w!r} W, buffer {buffer_j!r} J')
    limit = min(max(round(limit_w), MIN_LIMIT_W), MAX_LIMIT_W)
    buffer = min(max(round(buffer_j), 0), MAX_BUFFER_J)
    return _COMMAND.pack(int(enable) | int(restart) << 1, limit, buffer)


def decode_command(data: bytes) -> tuple[bool, bool, int, int]:
    """(enable, restart, limit [W], buffer [J]) of a 0x061 frame, as the board reads it.

    Raises:
        FrameLengthError: not 8 bytes.
    """
    _check_length(data)
    flags, limit, buffer = _COMMAND.unpack(data)
    return bool(flags & 1), bool(flags & 2), limit, buffer


def encode_feedback(errors: int, chassis_power_w: float, limit_w: float,
                    energy: float) -> bytes:
    """The 0x051 frame (the simulated controller's); energy 0..1 rounds to 1/255 steps.

    Raises:
        ValueRangeError: a NaN or infinite value, or energy outside 0..1.
    """
    if not all(math.isfinite(v) for v in (chassis_power_w, limit_w, energy)):
        raise ValueRangeError(f'supercap feedback: {chassis_power_w!r} W, {limit_w!r} W, '
                              f'{energy!r}')
    if not 0.0 <= energy <= 1.0:
        raise ValueRangeError(f'supercap energy {energy!r} outside 0..1')
    limit = min(max(round(limit_w), 0), 0xFFFF)
    return _FEEDBACK.pack(errors & 0xFF, chassis_power_w, limit, round(energy * 255))


def decode_feedback(data: bytes) -> CapFeedback:
    """A 0x051 frame's values.

    Raises:
        FrameLengthError: not 8 bytes.
        ValueRangeError: a NaN or infinite power.
    """
    _check_length(data)
    errors, power, limit, energy = _FEEDBACK.unpack(data)
    if not math.isfinite(power):
        raise ValueRangeError(f'supercap feedback: chassis power {power!r}')
    return CapFeedback(CapError(errors), power, limit, energy / 255)


def _check_length(data: bytes) -> None:
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'supercap frame of {len(data)} bytes, expected {FRAME_LENGTH}')
