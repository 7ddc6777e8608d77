"""AgileX Piper arm: per-joint MIT command frames 0x15A..0x15F with a 4-bit check value.

PROTOCOLS.md §3 (piper_sdk 0.6.1). Same bit packing as the MIT frame for position (16),
velocity, kp, kd (12 each), but torque has only 8 bits and the last nibble is a check::

    data[6] = kd[3:0] << 4 | t[7:4]
    data[7] = t[3:0] << 4 | (data[0] ^ ... ^ data[6]) & 0x0F

The check covers bytes 0..6 only (so not t's low nibble). Ranges are fixed by the SDK:
position ±12.5 rad, velocity ±45 rad/s, kp 0..500, kd −5..5, torque ±8 N·m (SDK since
2025-07; older SDKs/firmware used ±18 — UNVERIFIED which your arm runs, so the torque
range is a parameter: :data:`PIPER_MIT_LIMITS_LEGACY`).
"""

from __future__ import annotations

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
