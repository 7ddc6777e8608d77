"""Damiao (DM) motors: MIT, POS_VEL, VEL and POS_FORCE commands, feedback, system frames.

docs/PROTOCOLS.md §2. Commands go to ``motor_id + mode offset`` (MIT 0x000, POS_VEL 0x100,
VEL 0x200, POS_FORCE 0x300); feedback comes from the master id (MST_ID register) with::

    byte 0: low nibble motor id, high nibble state / error code
    byte 1-2: position 16 bit, byte 3-4[7:4]: velocity 12 bit, byte 4[3:0]-5: torque 12 bit
    byte 6: MOS temperature °C, byte 7: rotor (coil) temperature °C

The MIT ranges (PMAX/VMAX/TMAX) are motor registers; :data:`DM_MODEL_LIMITS` holds the
defaults of the official SDKs and :func:`dm_limits` lets a config override them. Where the
SDKs disagree (DM4340, DM4340_48V, DM6006, DM8006) the table follows the DMR SDK
(``DM_CAN.py`` / ``damiao.h``); read RID 21–23 from the motor and set them in the config.

UNVERIFIED: system frames in non-MIT modes go to ``id + mode offset`` by default (two
official sources); one official SDK sends them to the bare id, see :func:`system_frame_id`.
"""

from __future__ import annotations

import enum
import math
import struct
from typing import NamedTuple

from rm_base.hardware.errors import FrameLengthError, HardwareConfigError, ValueRangeError
from rm_base.hardware.protocols.mit import (
    FRAME_LENGTH,
    POSITION_BITS,
    TORQUE_BITS,
    VELOCITY_BITS,
    MitLimits,
    clamped_float_to_uint,
    uint_to_float,
)

#: Highest motor id (the feedback carries only its low nibble).
MAX_MOTOR_ID = 0x0F
#: Register access frame id (read 0x33, write 0x55, save 0xAA).
REGISTER_FRAME_ID = 0x7FF
VEL_FRAME_LENGTH = 4
#: POS_FORCE scales: velocity ×100 and current per-unit ×10000, both uint16.
POS_FORCE_VELOCITY_SCALE = 100.0
POS_FORCE_CURRENT_SCALE = 10000.0

_POS_VEL = struct.Struct('<ff')
_VEL = struct.Struct('<f')
_POS_FORCE = struct.Struct('<fHH')


class DmMode(enum.IntEnum):
    """Command frame id offset of each control mode (register CTRL_MODE 1..4)."""

    MIT = 0x000
    POS_VEL = 0x100
    VEL = 0x200
    POS_FORCE = 0x300


#: CTRL_MODE register (RID 10) value of each mode.
CTRL_MODE_REGISTER = {DmMode.MIT: 1, DmMode.POS_VEL: 2, DmMode.VEL: 3, DmMode.POS_FORCE: 4}


class DmState(enum.IntEnum):
    """High nibble of feedback byte 0.

    8..E are from DM's ``damiao.h``; 0, 1, 5, 6 from a secondary source (UNVERIFIED).
    """

    DISABLED = 0x0
    ENABLED = 0x1
    SENSOR_ERROR = 0x5
    PARAMETER_ERROR = 0x6
    OVER_VOLTAGE = 0x8
    UNDER_VOLTAGE = 0x9
    OVER_CURRENT = 0xA
    MOS_OVER_TEMPERATURE = 0xB
    COIL_OVER_TEMPERATURE = 0xC
    COMMUNICATION_LOST = 0xD
    OVERLOAD = 0xE


#: States that are faults (everything but disabled/enabled).
FAULT_STATES = frozenset(s for s in DmState if s > DmState.ENABLED)

#: Default MIT ranges per model (PMAX rad, VMAX rad/s, TMAX N·m) from the official SDKs.
DM_MODEL_LIMITS: dict[str, MitLimits] = {
    'DM3507': MitLimits(12.566, 50.0, 5.0),
    'DM4310': MitLimits(12.5, 30.0, 10.0),
    'DM4310_48V': MitLimits(12.5, 50.0, 10.0),
    'DM4340': MitLimits(12.5, 8.0, 28.0),  # DMT says VMAX 10
    'DM4340_48V': MitLimits(12.5, 10.0, 28.0),  # DMT says VMAX 20
    'DM6006': MitLimits(12.5, 45.0, 20.0),  # DMT says TMAX 12
    'DM8006': MitLimits(12.5, 45.0, 40.0),  # DMT says TMAX 20
    'DM8009': MitLimits(12.5, 45.0, 54.0),
    'DM10010L': MitLimits(12.5, 25.0, 200.0),
    'DM10010': MitLimits(12.5, 20.0, 200.0),
    'DMH3510': MitLimits(12.5, 280.0, 1.0),
    'DMG6220': MitLimits(12.5, 45.0, 10.0),
    'DMH6215': MitLimits(12.5, 45.0, 10.0),
}


def dm_limits(model: str, overrides: dict[str, float] | None = None) -> MitLimits:
    """Return the MIT ranges of ``model`` (case-insensitive), with config overrides.

    Args:
        model: e.g. ``'DM4310'`` or ``'dm8009'``.
        overrides: e.g. ``{'v_max': 10.0}`` read from the motor's registers.

    Raises:
        HardwareConfigError: unknown model or override.
    """
    key = model.upper()
    if key not in DM_MODEL_LIMITS:
        raise HardwareConfigError(
            f'unknown Damiao model {model!r}; known: {", ".join(DM_MODEL_LIMITS)}'
        )
    return DM_MODEL_LIMITS[key].with_overrides(overrides)


def _check_motor_id(motor_id: int) -> None:
    if isinstance(motor_id, bool) or not isinstance(motor_id, int) or not 0 <= motor_id <= 0x7FF:
        raise ValueRangeError(f'Damiao motor id {motor_id!r} outside 0..0x7FF')


def command_id(motor_id: int, mode: DmMode) -> int:
    """Return the command frame id of ``motor_id`` in ``mode``.

    Raises:
        ValueRangeError: motor id out of range.
    """
    _check_motor_id(motor_id)
    return motor_id + DmMode(mode)


def system_frame_id(motor_id: int, mode: DmMode, with_mode_offset: bool = True) -> int:
    """Return the id to send enable/disable/zero/clear-error frames to.

    Args:
        motor_id: CAN id (ESC_ID) of the motor.
        mode: the motor's control mode.
        with_mode_offset: True (default; DMR ``dm_motor_drv.c``, DMT ``damiao.py``) sends to
            ``id + offset``; False (DMR ``DM_CAN.py``) to the bare id. UNVERIFIED which
            firmware needs which; both agree in MIT mode.

    Raises:
        ValueRangeError: motor id out of range.
    """
    _check_motor_id(motor_id)
    return motor_id + (DmMode(mode) if with_mode_offset else 0)


class DmFeedback(NamedTuple):
    """One decoded Damiao feedback frame.

    Attributes:
        motor_id: low nibble of byte 0.
        state: high nibble of byte 0 (see :class:`DmState`).
        position: [rad], rotor side of the motor's own output (as the motor reports it).
        velocity: [rad/s].
        torque: [N·m].
        t_mos: driver MOSFET temperature [°C].
        t_rotor: coil temperature [°C].
    """

    motor_id: int
    state: int
    position: float
    velocity: float
    torque: float
    t_mos: int
    t_rotor: int


def decode_feedback(data: bytes | bytearray, limits: MitLimits) -> DmFeedback:
    """Decode a feedback frame (host side).

    Args:
        data: 8 data bytes.
        limits: the motor's PMAX/VMAX/TMAX.

    Raises:
        FrameLengthError: not 8 bytes.
    """
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'Damiao feedback frame must be 8 bytes, got {len(data)}')
    d0, d1, d2, d3, d4, d5, d6, d7 = data
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    return DmFeedback(
        d0 & 0x0F,
        d0 >> 4,
        uint_to_float((d1 << 8) | d2, -p, p, POSITION_BITS),
        uint_to_float((d3 << 4) | (d4 >> 4), -v, v, VELOCITY_BITS),
        uint_to_float(((d4 & 0x0F) << 8) | d5, -t, t, TORQUE_BITS),
        d6,
        d7,
    )


def encode_feedback(
    motor_id: int,
    state: int,
    *,
    position: float,
    velocity: float,
    torque: float,
    t_mos: int,
    t_rotor: int,
    limits: MitLimits,
) -> bytes:
    """Encode a feedback frame (device side); p/v/t saturate at the range ends.

    Values are rounded to the nearest step (the motor firmware's rounding is not public), so
    :func:`decode_feedback` -> :func:`encode_feedback` reproduces the bytes.

    Args:
        motor_id: 0..15 (only the low nibble is carried).
        state: 0..15 (see :class:`DmState`).
        position: [rad].
        velocity: [rad/s].
        torque: [N·m].
        t_mos: [°C], 0..255.
        t_rotor: [°C], 0..255.
        limits: the motor's PMAX/VMAX/TMAX.

    Raises:
        ValueRangeError: id/state/temperature out of range, or p/v/t not finite.
    """
    if not 0 <= motor_id <= MAX_MOTOR_ID or not 0 <= state <= 0x0F:
        raise ValueRangeError(f'Damiao feedback id {motor_id} / state {state} outside 0..15')
    if not (0 <= t_mos <= 0xFF and 0 <= t_rotor <= 0xFF):
        raise ValueRangeError(f'Damiao temperatures {t_mos}, {t_rotor} outside 0..255')
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    q = clamped_float_to_uint(position, -p, p, POSITION_BITS, 'Damiao position', nearest=True)
    dq = clamped_float_to_uint(velocity, -v, v, VELOCITY_BITS, 'Damiao velocity', nearest=True)
    tau = clamped_float_to_uint(torque, -t, t, TORQUE_BITS, 'Damiao torque', nearest=True)
    return bytes(
        (
            (state << 4) | motor_id,
            q >> 8,
            q & 0xFF,
            dq >> 4,
            ((dq & 0x0F) << 4) | (tau >> 8),
            tau & 0xFF,
            t_mos,
            t_rotor,
        )
    )


def _finite(x: float, name: str) -> float:
    if not math.isfinite(x):
        raise ValueRangeError(f'Damiao {name} {x!r} is not finite')
    return x


def pack_pos_vel(position: float, velocity_limit: float) -> bytes:
    """POS_VEL command (id 0x100 + id): position [rad] and velocity limit [rad/s], f32 LE.

    Raises:
        ValueRangeError: NaN or infinite input.
    """
    return _POS_VEL.pack(_finite(position, 'position'), _finite(velocity_limit, 'velocity'))


def unpack_pos_vel(data: bytes | bytearray) -> tuple[float, float]:
    """Decode a POS_VEL command into ``(position, velocity_limit)`` (device side).

    Raises:
        FrameLengthError: not 8 bytes.
    """
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'Damiao POS_VEL frame must be 8 bytes, got {len(data)}')
    return _POS_VEL.unpack(data)


def pack_vel(velocity: float, pad_to_8: bool = False) -> bytes:
    """VEL command (id 0x200 + id): velocity [rad/s], f32 LE.

    Args:
        velocity: [rad/s].
        pad_to_8: DLC 8 with four zero bytes (as DM_CAN.py) instead of DLC 4.

    Raises:
        ValueRangeError: NaN or infinite input.
    """
    data = _VEL.pack(_finite(velocity, 'velocity'))
    return data + b'\x00\x00\x00\x00' if pad_to_8 else data


def unpack_vel(data: bytes | bytearray) -> float:
    """Decode a VEL command (4 or 8 bytes) into velocity [rad/s] (device side).

    Raises:
        FrameLengthError: not 4 or 8 bytes.
    """
    if len(data) not in (VEL_FRAME_LENGTH, FRAME_LENGTH):
        raise FrameLengthError(f'Damiao VEL frame must be 4 or 8 bytes, got {len(data)}')
    return float(_VEL.unpack_from(data)[0])


def pack_pos_force(position: float, velocity: float, current_pu: float) -> bytes:
    """POS_FORCE command (id 0x300 + id).

    Args:
        position: [rad], f32 LE.
        velocity: speed limit [rad/s], 0..655.35, sent as uint16 ×100.
        current_pu: current limit per unit (1.0 = the motor's full current), 0..1, sent as
            uint16 ×10000.

    Raises:
        ValueRangeError: NaN/inf or a value outside its range.
    """
    _finite(position, 'position')
    v_raw = round(_finite(velocity, 'velocity') * POS_FORCE_VELOCITY_SCALE)
    i_raw = round(_finite(current_pu, 'current') * POS_FORCE_CURRENT_SCALE)
    if not 0 <= v_raw <= 0xFFFF:
        raise ValueRangeError(f'Damiao POS_FORCE velocity {velocity} outside 0..655.35 rad/s')
    if not 0 <= i_raw <= POS_FORCE_CURRENT_SCALE:
        raise ValueRangeError(f'Damiao POS_FORCE current {current_pu} outside 0..1 per unit')
    return _POS_FORCE.pack(position, v_raw, i_raw)


def unpack_pos_force(data: bytes | bytearray) -> tuple[float, float, float]:
    """Decode a POS_FORCE command into ``(position, velocity, current_pu)`` (device side).

    Raises:
        FrameLengthError: not 8 bytes.
    """
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'Damiao POS_FORCE frame must be 8 bytes, got {len(data)}')
    position, v_raw, i_raw = _POS_FORCE.unpack(data)
    return position, v_raw / POS_FORCE_VELOCITY_SCALE, i_raw / POS_FORCE_CURRENT_SCALE
