"""The MIT-mode command frame shared by Damiao motors and the MIT Cheetah firmware.

One 8-byte frame carries position (16 bit), velocity, kp, kd and torque (12 bit each),
each a float mapped linearly onto an unsigned integer over a range (docs/PROTOCOLS.md §2.3)::

    data[0..1] = q             data[2] = dq[11:4]     data[3] = dq[3:0] | kp[11:8]
    data[4]    = kp[7:0]       data[5] = kd[11:4]     data[6] = kd[3:0] | tau[11:8]
    data[7]    = tau[7:0]

The motor computes ``tau_out = kp*(q - q_meas) + kd*(dq - dq_meas) + tau``. The vendors'
C code does not clamp; :func:`pack_mit_command` clamps every field to its range first, so
an out-of-range value saturates instead of wrapping around.

Also here: the special frames (7 × 0xFF + a command byte) that enable, disable, zero and
clear errors, shared by Damiao and Cheetah (the Cheetah has no clear-error).
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Mapping
from typing import NamedTuple

from rm_base.hardware.errors import FrameLengthError, HardwareConfigError, ValueRangeError

FRAME_LENGTH = 8
POSITION_BITS = 16
VELOCITY_BITS = 12
KP_BITS = 12
KD_BITS = 12
TORQUE_BITS = 12
#: Gain ranges used by every Damiao and Cheetah firmware read.
KP_MAX = 500.0
KD_MAX = 5.0

_SYSTEM_PREFIX = b'\xff' * 7


class SystemCommand(enum.IntEnum):
    """Last byte of a special frame ``FF FF FF FF FF FF FF xx``."""

    CLEAR_ERROR = 0xFB
    ENABLE = 0xFC
    DISABLE = 0xFD
    SET_ZERO = 0xFE


@dataclasses.dataclass(frozen=True)
class MitLimits:
    """Float ranges of an MIT frame; they must match the motor's own registers.

    Position, velocity and torque are symmetric: ``[-p_max, p_max]`` and so on.

    Attributes:
        p_max: position range [rad].
        v_max: velocity range [rad/s].
        t_max: torque range [N·m].
        kp_min: lower end of kp [N·m/rad].
        kp_max: upper end of kp [N·m/rad].
        kd_min: lower end of kd [N·m·s/rad] (0 for Damiao, −5 for Piper).
        kd_max: upper end of kd [N·m·s/rad].
    """

    p_max: float
    v_max: float
    t_max: float
    kp_min: float = 0.0
    kp_max: float = KP_MAX
    kd_min: float = 0.0
    kd_max: float = KD_MAX

    def __post_init__(self) -> None:
        for name in ('p_max', 'v_max', 't_max', 'kp_max', 'kd_max'):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0.0):
                raise HardwareConfigError(f'MitLimits.{name} must be > 0, got {value!r}')
        for lo, hi in (('kp_min', 'kp_max'), ('kd_min', 'kd_max')):
            low = getattr(self, lo)
            ok = isinstance(low, int | float) and math.isfinite(low) and low < getattr(self, hi)
            if not ok:
                raise HardwareConfigError(f'MitLimits.{lo} must be finite and < {hi}, got {low!r}')

    def with_overrides(self, overrides: Mapping[str, object] | None) -> MitLimits:
        """Return a copy with some fields replaced (e.g. from a robot config).

        Raises:
            HardwareConfigError: unknown field or invalid value.
        """
        if not overrides:
            return self
        fields = {f.name for f in dataclasses.fields(self)}
        unknown = set(overrides) - fields
        if unknown:
            raise HardwareConfigError(
                f'unknown MIT limit(s) {sorted(unknown)}; known: {sorted(fields)}'
            )
        values: dict[str, float] = {}
        for key, value in overrides.items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise HardwareConfigError(f'MIT limit {key} must be a number, got {value!r}')
            values[key] = float(value)
        return dataclasses.replace(self, **values)


class MitCommand(NamedTuple):
    """One MIT command.

    Attributes:
        position: [rad].
        velocity: [rad/s].
        kp: [N·m/rad].
        kd: [N·m·s/rad].
        torque: feed-forward [N·m].
    """

    position: float
    velocity: float
    kp: float
    kd: float
    torque: float


def float_to_uint(x: float, x_min: float, x_max: float, bits: int) -> int:
    """Map ``x`` in ``[x_min, x_max]`` onto ``0 .. 2**bits - 1``, truncating like the C code.

    Args:
        x: value, inside the range.
        x_min: lower end of the range.
        x_max: upper end of the range.
        bits: field width.

    Returns:
        The unsigned field value.

    Raises:
        ValueRangeError: x is NaN, infinite, or outside the range.
    """
    if not x_min <= x <= x_max:  # also catches NaN
        raise ValueRangeError(f'{x!r} outside [{x_min}, {x_max}]')
    return _f2u(x, x_min, x_max, bits)


def _f2u(x: float, x_min: float, x_max: float, bits: int) -> int:
    top = (1 << bits) - 1
    u = int((x - x_min) * top / (x_max - x_min))
    # (x_max - x_min) * top / (x_max - x_min) can round a hair below top.
    return top if u > top else u


def uint_to_float(u: int, x_min: float, x_max: float, bits: int) -> float:
    """Map a field value ``0 .. 2**bits - 1`` back onto ``[x_min, x_max]``.

    Raises:
        ValueRangeError: u outside the field.
    """
    top = (1 << bits) - 1
    if not 0 <= u <= top:
        raise ValueRangeError(f'{u} outside the {bits}-bit field')
    return u * (x_max - x_min) / top + x_min


def clamped_float_to_uint(
    x: float, x_min: float, x_max: float, bits: int, name: str, *, nearest: bool = False
) -> int:
    """Like :func:`float_to_uint`, but saturate ``x`` at the range ends first.

    Args:
        x: value; outside the range it is clamped.
        x_min: lower end of the range.
        x_max: upper end of the range.
        bits: field width.
        name: field name for the error message.
        nearest: round to the nearest step instead of truncating. The device-side feedback
            encoders use it so that decode -> encode is exact; commands truncate as the
            vendors' code does.

    Returns:
        The unsigned field value.

    Raises:
        ValueRangeError: x is NaN or infinite.
    """
    if not math.isfinite(x):
        raise ValueRangeError(f'{name} {x!r} is not finite')
    x = x_min if x < x_min else x_max if x > x_max else x
    if nearest:
        return round((x - x_min) * ((1 << bits) - 1) / (x_max - x_min))
    return _f2u(x, x_min, x_max, bits)


def mit_command_uints(cmd: MitCommand, limits: MitLimits) -> tuple[int, int, int, int, int]:
    """Clamp each field of ``cmd`` to ``limits`` and map it to its unsigned field.

    Returns:
        ``(q16, dq12, kp12, kd12, tau12)``.

    Raises:
        ValueRangeError: a field is NaN or infinite.
    """
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    return (
        clamped_float_to_uint(cmd.position, -p, p, POSITION_BITS, 'MIT position'),
        clamped_float_to_uint(cmd.velocity, -v, v, VELOCITY_BITS, 'MIT velocity'),
        clamped_float_to_uint(cmd.kp, limits.kp_min, limits.kp_max, KP_BITS, 'MIT kp'),
        clamped_float_to_uint(cmd.kd, limits.kd_min, limits.kd_max, KD_BITS, 'MIT kd'),
        clamped_float_to_uint(cmd.torque, -t, t, TORQUE_BITS, 'MIT torque'),
    )


def pack_mit_uints(q: int, dq: int, kp: int, kd: int, tau: int) -> bytes:
    """Pack the five unsigned fields (16/12/12/12/12 bits) into 8 bytes.

    Raises:
        ValueRangeError: a field does not fit its width.
    """
    if not (
        0 <= q <= 0xFFFF
        and 0 <= dq <= 0xFFF
        and 0 <= kp <= 0xFFF
        and 0 <= kd <= 0xFFF
        and 0 <= tau <= 0xFFF
    ):
        raise ValueRangeError(f'MIT fields {(q, dq, kp, kd, tau)} do not fit 16/12/12/12/12 bits')
    return bytes(
        (
            q >> 8,
            q & 0xFF,
            dq >> 4,
            ((dq & 0xF) << 4) | (kp >> 8),
            kp & 0xFF,
            kd >> 4,
            ((kd & 0xF) << 4) | (tau >> 8),
            tau & 0xFF,
        )
    )


def unpack_mit_uints(data: bytes | bytearray) -> tuple[int, int, int, int, int]:
    """Split an 8-byte MIT command into ``(q16, dq12, kp12, kd12, tau12)`` (device side).

    Raises:
        FrameLengthError: not 8 bytes.
    """
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'MIT command frame must be 8 bytes, got {len(data)}')
    d0, d1, d2, d3, d4, d5, d6, d7 = data
    return (
        (d0 << 8) | d1,
        (d2 << 4) | (d3 >> 4),
        ((d3 & 0xF) << 8) | d4,
        (d5 << 4) | (d6 >> 4),
        ((d6 & 0xF) << 8) | d7,
    )


def pack_mit_command(cmd: MitCommand, limits: MitLimits) -> bytes:
    """Clamp and pack one MIT command (host side).

    Args:
        cmd: the command; fields outside ``limits`` saturate at the range ends.
        limits: ranges, identical to the motor's registers.

    Returns:
        8 data bytes.

    Raises:
        ValueRangeError: a field is NaN or infinite.
    """
    return pack_mit_uints(*mit_command_uints(cmd, limits))


def unpack_mit_command(data: bytes | bytearray, limits: MitLimits) -> MitCommand:
    """Decode an 8-byte MIT command into floats (device side).

    Raises:
        FrameLengthError: not 8 bytes.
    """
    q, dq, kp, kd, tau = unpack_mit_uints(data)
    p, v, t = limits.p_max, limits.v_max, limits.t_max
    return MitCommand(
        uint_to_float(q, -p, p, POSITION_BITS),
        uint_to_float(dq, -v, v, VELOCITY_BITS),
        uint_to_float(kp, limits.kp_min, limits.kp_max, KP_BITS),
        uint_to_float(kd, limits.kd_min, limits.kd_max, KD_BITS),
        uint_to_float(tau, -t, t, TORQUE_BITS),
    )


def system_frame(command: SystemCommand | int) -> bytes:
    """Return the 8 data bytes of a special frame (enable, disable, set zero, clear error).

    Raises:
        ValueRangeError: not a known :class:`SystemCommand`.
    """
    try:
        command = SystemCommand(command)
    except ValueError as err:
        raise ValueRangeError(f'unknown MIT system command {command!r}') from err
    return _SYSTEM_PREFIX + bytes((command,))


def parse_system_frame(data: bytes | bytearray) -> SystemCommand | None:
    """Return the :class:`SystemCommand` of a special frame, or None for any other frame.

    An 8-byte frame that is not ``FF×7 + FB..FE`` is an MIT command (device side).

    Raises:
        FrameLengthError: not 8 bytes.
    """
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'MIT frame must be 8 bytes, got {len(data)}')
    if data[:7] != _SYSTEM_PREFIX or data[7] < SystemCommand.CLEAR_ERROR or data[7] == 0xFF:
        return None
    return SystemCommand(data[7])
