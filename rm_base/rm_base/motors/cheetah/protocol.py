"""MIT Cheetah (Ben Katz) motor firmware: same command frame as Damiao, different reply.

docs/PROTOCOLS.md §2.7. Commands use :func:`rm_base.hardware.protocols.mit.pack_mit_command`
sent to the motor's CAN id; special frames are enable (FC), disable (FD) and set zero
(FE) — there is **no clear-error** frame. Every received frame is answered to the master
id (default 0) with::

    6 bytes (mbed firmware):  [id, p_hi, p_lo, v[11:4], v[3:0] | t[11:8], t[7:0]]
    7 bytes (STM32 firmware): the same + bus voltage, float_to_uint(vb, 0, 40, 8)

Byte 0 is the full motor id (no error nibble) and there are no temperatures. Ranges
differ between firmware versions; :data:`CHEETAH_DEFAULT_LIMITS` is P ±12.5, V ±65,
T ±18 (bgkatz/motorcontrol defaults with T from the mbed firmware, rm_control's table)
and must be set to the motor's values in the config.
"""

from __future__ import annotations

from typing import NamedTuple

from rm_base.hardware.errors import FrameLengthError, ValueRangeError
from rm_base.hardware.protocols.mit import (
    POSITION_BITS,
    TORQUE_BITS,
    VELOCITY_BITS,
    MitLimits,
    SystemCommand,
    clamped_float_to_uint,
    system_frame,
    uint_to_float,
)

REPLY_LENGTH = 6
REPLY_LENGTH_WITH_VOLTAGE = 7
#: Reply frame id: the firmware's CAN_MASTER, default 0.
DEFAULT_MASTER_ID = 0x000
#: Bus voltage field: 8 bits over 0..40 V.
BUS_VOLTAGE_MAX = 40.0
BUS_VOLTAGE_BITS = 8

CHEETAH_DEFAULT_LIMITS = MitLimits(12.5, 65.0, 18.0)

#: The special frames the Cheetah firmware knows.
CHEETAH_SYSTEM_COMMANDS = frozenset(
    {SystemCommand.ENABLE, SystemCommand.DISABLE, SystemCommand.SET_ZERO}
)


class CheetahReply(NamedTuple):
    """One decoded reply.

    Attributes:
        motor_id: full id byte.
        position: [rad].
        velocity: [rad/s].
        torque: [N·m].
        bus_voltage: [V], or None for the 6-byte reply.
    """

    motor_id: int
    position: float
    velocity: float
    torque: float
    bus_voltage: float | None


def cheetah_system_frame(command: SystemCommand | int) -> bytes:
    """Return the data of an enable / disable / set-zero frame.

    Raises:
        ValueRangeError: the command is not one the Cheetah firmware knows (clear error).
    """
    if command not in CHEETAH_SYSTEM_COMMANDS:
        raise ValueRangeError(
            f'the MIT Cheetah firmware has no system command {command!r} (no clear-error)'
        )
    return system_frame(command)


def decode_reply(
    data: bytes | bytearray, limits: MitLimits = CHEETAH_DEFAULT_LIMITS
) -> CheetahReply:
    """Decode a 6- or 7-byte reply (host side).

    Raises:
        FrameLengthError: not 6 or 7 bytes.
    """
    n = len(data)
    if n not in (REPLY_LENGTH, REPLY_LENGTH_WITH_VOLTAGE):
        raise FrameLengthError(f'Cheetah reply must be 6 or 7 bytes, got {n}')
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    d4 = data[4]
    return CheetahReply(
        data[0],
        uint_to_float((data[1] << 8) | data[2], -p, p, POSITION_BITS),
        uint_to_float((data[3] << 4) | (d4 >> 4), -v, v, VELOCITY_BITS),
        uint_to_float(((d4 & 0x0F) << 8) | data[5], -t, t, TORQUE_BITS),
        uint_to_float(data[6], 0.0, BUS_VOLTAGE_MAX, BUS_VOLTAGE_BITS) if n == 7 else None,
    )


def encode_reply(
    motor_id: int,
    *,
    position: float,
    velocity: float,
    torque: float,
    bus_voltage: float | None = None,
    limits: MitLimits = CHEETAH_DEFAULT_LIMITS,
) -> bytes:
    """Encode a reply (device side); values saturate and round to the nearest step.

    Args:
        motor_id: 0..255.
        position: [rad].
        velocity: [rad/s].
        torque: [N·m].
        bus_voltage: [V] for the 7-byte reply, None for the 6-byte one.
        limits: the motor's ranges.

    Raises:
        ValueRangeError: id out of range or a value not finite.
    """
    if not 0 <= motor_id <= 0xFF:
        raise ValueRangeError(f'Cheetah motor id {motor_id} outside 0..255')
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    q = clamped_float_to_uint(position, -p, p, POSITION_BITS, 'Cheetah position', nearest=True)
    dq = clamped_float_to_uint(velocity, -v, v, VELOCITY_BITS, 'Cheetah velocity', nearest=True)
    tau = clamped_float_to_uint(torque, -t, t, TORQUE_BITS, 'Cheetah torque', nearest=True)
    out = bytes((motor_id, q >> 8, q & 0xFF, dq >> 4, ((dq & 0x0F) << 4) | (tau >> 8), tau & 0xFF))
    if bus_voltage is None:
        return out
    vb = clamped_float_to_uint(
        bus_voltage, 0.0, BUS_VOLTAGE_MAX, BUS_VOLTAGE_BITS, 'bus voltage', nearest=True
    )
    return out + bytes((vb,))
