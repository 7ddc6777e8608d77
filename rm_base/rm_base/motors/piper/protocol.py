"""AgileX Piper arm: per-joint MIT command frames 0x15A..0x15F with a 4-bit check value.

docs/PROTOCOLS.md §3 (piper_sdk 0.6.1). Same bit packing as the MIT frame for position (16),
velocity, kp, kd (12 each), but torque has only 8 bits and the last nibble is a check::

    data[6] = kd[3:0] << 4 | t[7:4]
    data[7] = t[3:0] << 4 | (data[0] ^ ... ^ data[6]) & 0x0F

The check covers bytes 0..6 only (so not t's low nibble). Ranges are fixed by the SDK:
position ±12.5 rad, velocity ±45 rad/s, kp 0..500, kd −5..5, torque ±8 N·m (SDK since
2025-07; older SDKs/firmware used ±18 — UNVERIFIED which your arm runs, so the torque
range is a joint option, ±18 by default: :data:`PIPER_MIT_LIMITS_LEGACY`).

Feedback (not in docs/PROTOCOLS.md; from the piper_sdk 0.6.1 message docstrings, UNVERIFIED on
an arm): joint angles in 0x2A5/0x2A6/0x2A7, two joints per frame as int32 big-endian in
0.001°; per-joint "high-speed" driver feedback in 0x251..0x256: speed int16 BE in
0.001 rad/s, current int16 BE in 0.001 A, position int32 BE (unit unclear, not decoded
into SI). The SDK turns current into effort with a fixed N·m/A coefficient per joint
(:data:`EFFORT_PER_AMP`).
"""

from __future__ import annotations

import math
import struct

from rm_base.hardware.errors import ChecksumError, FrameLengthError, ValueRangeError
from rm_base.hardware.protocols.mit import (
    FRAME_LENGTH,
    KD_BITS,
    KP_BITS,
    POSITION_BITS,
    VELOCITY_BITS,
    MitCommand,
    MitLimits,
    clamped_float_to_uint,
    uint_to_float,
)

#: Joint 1..6 command ids: 0x15A + (joint - 1).
JOINT_MIT_BASE_ID = 0x15A
JOINT_COUNT = 6
TORQUE_BITS = 8
#: MotionCtrl_2 frame that switches the arm into MIT mode (sent by the SDK demo).
MOTION_CTRL_2_ID = 0x151

#: Joint angle feedback ids: 0x2A5 joints 1-2, 0x2A6 joints 3-4, 0x2A7 joints 5-6.
JOINT_FEEDBACK_BASE_ID = 0x2A5
#: Driver high-speed feedback ids: 0x251 + (joint - 1).
HIGH_SPEED_FEEDBACK_BASE_ID = 0x251
JOINT_ANGLE_RAD_PER_RAW = math.radians(0.001)
HIGH_SPEED_RAD_PER_S_PER_RAW = 0.001
HIGH_SPEED_AMPS_PER_RAW = 0.001
#: piper_sdk ``ArmMsgFeedbackHighSpd.cal_effort``: effort [N·m] per current [A], joints 1..6.
EFFORT_PER_AMP = (1.18125, 1.18125, 1.18125, 0.95844, 0.95844, 0.95844)

_JOINT_FEEDBACK = struct.Struct('>ii')
_HIGH_SPEED = struct.Struct('>hhi')

PIPER_MIT_LIMITS = MitLimits(12.5, 45.0, 8.0, kd_min=-5.0)
PIPER_MIT_LIMITS_LEGACY = MitLimits(12.5, 45.0, 18.0, kd_min=-5.0)


def joint_command_id(joint: int) -> int:
    """Return the MIT command id of ``joint`` (1..6).

    Raises:
        ValueRangeError: joint out of range.
    """
    if isinstance(joint, bool) or not isinstance(joint, int) or not 1 <= joint <= JOINT_COUNT:
        raise ValueRangeError(f'Piper joint {joint!r} outside 1..{JOINT_COUNT}')
    return JOINT_MIT_BASE_ID + joint - 1


def check_nibble(data: bytes | bytearray) -> int:
    """XOR of bytes 0..6, low nibble."""
    x = 0
    for b in data[:7]:
        x ^= b
    return x & 0x0F


def pack_joint_mit(
    joint: int, cmd: MitCommand, limits: MitLimits = PIPER_MIT_LIMITS
) -> tuple[int, bytes]:
    """Clamp and pack one joint MIT command (host side).

    Args:
        joint: 1..6.
        cmd: position [rad], velocity [rad/s], kp, kd, torque [N·m]; clamped to ``limits``.
        limits: the SDK's fixed ranges (torque ±8, or ±18 for old firmware).

    Returns:
        ``(arbitration_id, data)``.

    Raises:
        ValueRangeError: joint out of range, or a field NaN/infinite.
    """
    can_id = joint_command_id(joint)
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    q = clamped_float_to_uint(cmd.position, -p, p, POSITION_BITS, 'Piper position')
    dq = clamped_float_to_uint(cmd.velocity, -v, v, VELOCITY_BITS, 'Piper velocity')
    kp = clamped_float_to_uint(cmd.kp, limits.kp_min, limits.kp_max, KP_BITS, 'Piper kp')
    kd = clamped_float_to_uint(cmd.kd, limits.kd_min, limits.kd_max, KD_BITS, 'Piper kd')
    tau = clamped_float_to_uint(cmd.torque, -t, t, TORQUE_BITS, 'Piper torque')
    head = bytes(
        (
            q >> 8,
            q & 0xFF,
            dq >> 4,
            ((dq & 0xF) << 4) | (kp >> 8),
            kp & 0xFF,
            kd >> 4,
            ((kd & 0xF) << 4) | (tau >> 4),
        )
    )
    return can_id, head + bytes((((tau & 0xF) << 4) | check_nibble(head),))


def unpack_joint_mit(
    arbitration_id: int, data: bytes | bytearray, limits: MitLimits = PIPER_MIT_LIMITS
) -> tuple[int, MitCommand]:
    """Decode a joint MIT command and verify its check nibble (device side).

    Returns:
        ``(joint, command)``.

    Raises:
        ValueRangeError: the id is not a joint MIT id.
        FrameLengthError: not 8 bytes.
        ChecksumError: the check nibble does not match.
    """
    joint = arbitration_id - JOINT_MIT_BASE_ID + 1
    if not 1 <= joint <= JOINT_COUNT:
        raise ValueRangeError(f'0x{arbitration_id:03X} is not a Piper joint MIT id')
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'Piper joint MIT frame must be 8 bytes, got {len(data)}')
    expected = check_nibble(data)
    if data[7] & 0x0F != expected:
        raise ChecksumError(
            f'Piper joint {joint} MIT frame check 0x{data[7] & 0x0F:X}, expected 0x{expected:X}'
        )
    d0, d1, d2, d3, d4, d5, d6, d7 = data
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    return joint, MitCommand(
        uint_to_float((d0 << 8) | d1, -p, p, POSITION_BITS),
        uint_to_float((d2 << 4) | (d3 >> 4), -v, v, VELOCITY_BITS),
        uint_to_float(((d3 & 0xF) << 8) | d4, limits.kp_min, limits.kp_max, KP_BITS),
        uint_to_float((d5 << 4) | (d6 >> 4), limits.kd_min, limits.kd_max, KD_BITS),
        uint_to_float(((d6 & 0xF) << 4) | (d7 >> 4), -t, t, TORQUE_BITS),
    )


def joint_feedback_id(joint: int) -> tuple[int, int]:
    """Return ``(arbitration_id, index)`` of ``joint``'s angle in the joint feedback frames.

    Raises:
        ValueRangeError: joint out of range.
    """
    joint_command_id(joint)
    return JOINT_FEEDBACK_BASE_ID + (joint - 1) // 2, (joint - 1) % 2


def decode_joint_feedback(arbitration_id: int, data: bytes | bytearray) -> tuple[int, float, float]:
    """Decode a joint angle frame into ``(first_joint, angle_a, angle_b)`` [rad].

    Raises:
        ValueRangeError: not a joint feedback id.
        FrameLengthError: not 8 bytes.
    """
    index = arbitration_id - JOINT_FEEDBACK_BASE_ID
    if not 0 <= index < JOINT_COUNT // 2:
        raise ValueRangeError(f'0x{arbitration_id:03X} is not a Piper joint feedback id')
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'Piper joint feedback must be 8 bytes, got {len(data)}')
    a, b = _JOINT_FEEDBACK.unpack(data)
    return 2 * index + 1, a * JOINT_ANGLE_RAD_PER_RAW, b * JOINT_ANGLE_RAD_PER_RAW


def encode_joint_feedback(first_joint: int, angle_a: float, angle_b: float) -> tuple[int, bytes]:
    """Encode a joint angle frame (arm side) for joints ``first_joint`` and the next.

    Raises:
        ValueRangeError: first_joint not 1, 3 or 5, or an angle not finite / not int32.
    """
    if first_joint not in (1, 3, 5):
        raise ValueRangeError(f'Piper joint feedback starts at joint 1, 3 or 5, not {first_joint}')
    raws = []
    for angle in (angle_a, angle_b):
        if not math.isfinite(angle):
            raise ValueRangeError(f'Piper joint angle {angle!r} is not finite')
        raw = round(angle / JOINT_ANGLE_RAD_PER_RAW)
        if not -(2**31) <= raw < 2**31:
            raise ValueRangeError(f'Piper joint angle {angle} does not fit int32')
        raws.append(raw)
    return JOINT_FEEDBACK_BASE_ID + first_joint // 2, _JOINT_FEEDBACK.pack(*raws)


def decode_high_speed_feedback(
    arbitration_id: int, data: bytes | bytearray
) -> tuple[int, float, float, int]:
    """Decode driver feedback into ``(joint, velocity [rad/s], current [A], position_raw)``.

    Raises:
        ValueRangeError: not a high-speed feedback id.
        FrameLengthError: not 8 bytes.
    """
    joint = arbitration_id - HIGH_SPEED_FEEDBACK_BASE_ID + 1
    if not 1 <= joint <= JOINT_COUNT:
        raise ValueRangeError(f'0x{arbitration_id:03X} is not a Piper high-speed feedback id')
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'Piper high-speed feedback must be 8 bytes, got {len(data)}')
    speed, current, position = _HIGH_SPEED.unpack(data)
    return (
        joint,
        speed * HIGH_SPEED_RAD_PER_S_PER_RAW,
        current * HIGH_SPEED_AMPS_PER_RAW,
        position,
    )


def encode_high_speed_feedback(
    joint: int, velocity: float, current: float, position_raw: int = 0
) -> tuple[int, bytes]:
    """Encode driver feedback (arm side); velocity and current saturate at int16.

    Raises:
        ValueRangeError: joint out of range, or a value not finite.
    """
    joint_command_id(joint)
    if not (math.isfinite(velocity) and math.isfinite(current)):
        raise ValueRangeError(f'Piper feedback {velocity!r}, {current!r} not finite')
    speed = max(-0x8000, min(0x7FFF, round(velocity / HIGH_SPEED_RAD_PER_S_PER_RAW)))
    amps = max(-0x8000, min(0x7FFF, round(current / HIGH_SPEED_AMPS_PER_RAW)))
    return HIGH_SPEED_FEEDBACK_BASE_ID + joint - 1, _HIGH_SPEED.pack(speed, amps, position_raw)
