"""DJI RoboMaster ESCs and motors over CAN: C620 (M3508), C610 (M2006), GM6020.

Why one module: both directions (host and simulated ESC) for three ESC kinds, with their
ids, scales and checks.

Both directions are here, because the simulator plays the motor with the same code:

* host side: :func:`pack_command` (one shared frame for up to four motors),
  :func:`decode_feedback`;
* device side: :func:`unpack_command`, :func:`encode_feedback`.

Frame layouts, ids and scales are from docs/PROTOCOLS.md §1 (DJI Dev-Board-C examples, C610
manual, rm_control). Command frames carry four big-endian int16 values, one per slot;
feedback frames carry rotor angle (0..8191 ticks), rotor speed (rpm, before any gearbox),
torque current (raw) and temperature (°C; the C610 sends none).

UNVERIFIED items are configurable through :func:`make_dji_spec`:

* GM6020 voltage-mode limit: ±25000 (new firmware; default) or ±30000 (DJI 2019 example);
* GM6020 current-mode scale: 3 A per 16384 (default, the safer of the two: if the true scale
  is 1.62 A the motor gets less current than asked, never more) or 1.62 A;
* GM6020 volts per raw (24 V per 25000 raw, gm6020_can);
* C610 feedback current scale (10 A per 10000 raw, rm_control).
"""

from __future__ import annotations

import dataclasses
import enum
import math
import struct
from collections.abc import Iterable, Sequence
from typing import Any, NamedTuple

from rm_base.hardware.errors import FrameLengthError, HardwareConfigError, ValueRangeError

# --- Frame ids -------------------------------------------------------------------------
#: C620/C610 command frame for ESC ids 1–4.
CMD_ID_C6X0_1_4 = 0x200
#: C620/C610 command frame for ESC ids 5–8 (shared with GM6020 voltage ids 1–4).
CMD_ID_C6X0_5_8 = 0x1FF
#: GM6020 voltage-mode command frames, ids 1–4 and 5–7.
CMD_ID_GM6020_VOLTAGE_1_4 = 0x1FF
CMD_ID_GM6020_VOLTAGE_5_7 = 0x2FF
#: GM6020 current-mode command frames, ids 1–4 and 5–7 (current loop enabled in the
#: RoboMaster Assistant first).
CMD_ID_GM6020_CURRENT_1_4 = 0x1FE
CMD_ID_GM6020_CURRENT_5_7 = 0x2FE
#: C620 "quick id setting" frame (all data bytes zero).
CMD_ID_C620_QUICK_ID = 0x700
#: Feedback id = base + ESC id.
FEEDBACK_BASE_C6X0 = 0x200
FEEDBACK_BASE_GM6020 = 0x204

#: Every DJI command frame id.
COMMAND_IDS = frozenset(
    {
        CMD_ID_C6X0_1_4,
        CMD_ID_C6X0_5_8,
        CMD_ID_GM6020_VOLTAGE_5_7,
        CMD_ID_GM6020_CURRENT_1_4,
        CMD_ID_GM6020_CURRENT_5_7,
    }
)

# --- Layout and scales -----------------------------------------------------------------
FRAME_LENGTH = 8
SLOTS_PER_FRAME = 4
INT16_MAX = 0x7FFF
INT16_MIN = -0x8000
#: Rotor encoder ticks per mechanical revolution (angle field 0..8191).
ENCODER_TICKS_PER_REV = 8192
RAD_PER_TICK = 2.0 * math.pi / ENCODER_TICKS_PER_REV
RAD_PER_S_PER_RPM = 2.0 * math.pi / 60.0

#: C620: ±16384 raw ↔ ±20 A.
C620_RAW_LIMIT = 16384
C620_AMPS_PER_RAW = 20.0 / 16384.0
#: C610: ±10000 raw ↔ ±10 A (C610 manual p.8).
C610_RAW_LIMIT = 10000
C610_AMPS_PER_RAW = 10.0 / 10000.0
#: GM6020 voltage mode: the safe limit for current firmware, and the hard ceiling.
GM6020_VOLTAGE_RAW_LIMIT_SAFE = 25000
GM6020_VOLTAGE_RAW_LIMIT_MAX = 30000
#: GM6020 voltage per raw: 24 V ↔ 25000 raw (gm6020_can; UNVERIFIED).
GM6020_VOLTS_PER_RAW = 24.0 / 25000.0
#: GM6020 current mode: ±16384 raw; full-scale current 3 A (safe default) or 1.62 A.
GM6020_CURRENT_RAW_LIMIT = 16384
GM6020_CURRENT_FULL_SCALE_A_SAFE = 3.0
GM6020_CURRENT_FULL_SCALE_A_ALT = 1.62
GM6020_AMPS_PER_RAW_SAFE = GM6020_CURRENT_FULL_SCALE_A_SAFE / 16384.0

_COMMAND = struct.Struct('>4h')
_FEEDBACK = struct.Struct('>HhhBx')


class DjiKind(enum.Enum):
    """The four ways a DJI motor is driven; each has its own frames and scales."""

    C620 = 'c620'
    C610 = 'c610'
    GM6020_VOLTAGE = 'gm6020_voltage'
    GM6020_CURRENT = 'gm6020_current'


@dataclasses.dataclass(frozen=True)
class DjiSpec:
    """Ids, limits and scales of one :class:`DjiKind`.

    Attributes:
        kind: the ESC kind.
        max_id: highest ESC id (8 for C620/C610, 7 for GM6020).
        command_ids: command frame ids for ids 1–4 and for ids 5 and up.
        feedback_base: feedback frame id = feedback_base + ESC id.
        raw_limit: commands are clamped to ±raw_limit.
        si_per_raw: amperes (current kinds) or volts (GM6020 voltage) per command raw unit.
        command_unit: ``'A'`` or ``'V'``.
        feedback_amps_per_raw: amperes per raw unit of the feedback current field.
        has_temperature: False for the C610, whose byte 6 is "Null".
    """

    kind: DjiKind
    max_id: int
    command_ids: tuple[int, int]
    feedback_base: int
    raw_limit: int
    si_per_raw: float
    command_unit: str
    feedback_amps_per_raw: float
    has_temperature: bool

    def check_id(self, esc_id: int) -> None:
        """Raise :class:`ValueRangeError` unless ``1 <= esc_id <= max_id``.

        Args:
            esc_id: ESC / motor id as set on the device.

        Raises:
            ValueRangeError: the id is out of range or not an int.
        """
        if isinstance(esc_id, bool) or not isinstance(esc_id, int):
            raise ValueRangeError(f'{self.kind.value}: ESC id must be an int, got {esc_id!r}')
        if not 1 <= esc_id <= self.max_id:
            raise ValueRangeError(
                f'{self.kind.value}: ESC id {esc_id} out of range 1..{self.max_id}'
            )

    def command_slot(self, esc_id: int) -> tuple[int, int]:
        """Return ``(arbitration_id, slot)`` of the command frame for ``esc_id``.

        Args:
            esc_id: ESC id, 1..max_id.

        Returns:
            The command frame id and the slot index 0..3 in it.

        Raises:
            ValueRangeError: the id is out of range.
        """
        self.check_id(esc_id)
        return self.command_ids[(esc_id - 1) // SLOTS_PER_FRAME], (esc_id - 1) % SLOTS_PER_FRAME

    def feedback_id(self, esc_id: int) -> int:
        """Return the feedback frame id of ``esc_id``.

        Raises:
            ValueRangeError: the id is out of range.
        """
        self.check_id(esc_id)
        return self.feedback_base + esc_id

    def esc_id_from_feedback(self, arbitration_id: int) -> int | None:
        """Return the ESC id a feedback frame id belongs to, or None if it is not one."""
        esc_id = arbitration_id - self.feedback_base
        return esc_id if 1 <= esc_id <= self.max_id else None

    def raw_from_si(self, value: float) -> int:
        """Convert a command in A (or V) to raw, rounded and clamped to ±raw_limit.

        Args:
            value: current [A] or, for GM6020 voltage mode, voltage [V].

        Returns:
            Raw command value for :func:`pack_command`.

        Raises:
            ValueRangeError: value is NaN or infinite.
        """
        if not math.isfinite(value):
            raise ValueRangeError(f'{self.kind.value}: command {value!r} is not finite')
        raw = round(value / self.si_per_raw)
        limit = self.raw_limit
        return limit if raw > limit else -limit if raw < -limit else raw

    def si_from_raw(self, raw: int) -> float:
        """Convert a raw command back to A (or V)."""
        return raw * self.si_per_raw

    def feedback_amps(self, current_raw: int) -> float:
        """Convert the feedback current field to amperes."""
        return current_raw * self.feedback_amps_per_raw


def make_dji_spec(
    kind: DjiKind | str,
    *,
    raw_limit: int | None = None,
    si_per_raw: float | None = None,
    feedback_amps_per_raw: float | None = None,
) -> DjiSpec:
    """Build the spec of ``kind``, optionally overriding the UNVERIFIED numbers.

    Args:
        kind: a :class:`DjiKind` or its value (``'c620'``, ``'gm6020_voltage'``...).
        raw_limit: command clamp; at most the hard limit of the kind (C620 16384,
            C610 10000, GM6020 voltage 30000, GM6020 current 16384). GM6020 voltage
            defaults to 25000.
        si_per_raw: A (or V for GM6020 voltage) per command raw unit. For the GM6020 in
            current mode pass ``1.62 / 16384`` to use the alternative scale.
        feedback_amps_per_raw: A per raw unit of the feedback current field.

    Returns:
        The spec.

    Raises:
        HardwareConfigError: unknown kind or an override out of range.
    """
    try:
        kind = DjiKind(kind)
    except ValueError as err:
        known = ', '.join(k.value for k in DjiKind)
        raise HardwareConfigError(f'unknown DJI kind {kind!r}; known: {known}') from err
    base = _DEFAULT_SPECS[kind]
    hard_limit = _HARD_RAW_LIMITS[kind]
    changes: dict[str, Any] = {}
    if raw_limit is not None:
        if isinstance(raw_limit, bool) or not isinstance(raw_limit, int):
            raise HardwareConfigError(f'{kind.value}: raw_limit must be an int, got {raw_limit!r}')
        if not 0 < raw_limit <= hard_limit:
            raise HardwareConfigError(
                f'{kind.value}: raw_limit {raw_limit} out of range 1..{hard_limit}'
            )
        changes['raw_limit'] = raw_limit
    overrides = (('si_per_raw', si_per_raw), ('feedback_amps_per_raw', feedback_amps_per_raw))
    for name, value in overrides:
        if value is None:
            continue
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0.0):
            raise HardwareConfigError(f'{kind.value}: {name} must be > 0, got {value!r}')
        changes[name] = float(value)
    return dataclasses.replace(base, **changes) if changes else base


_DEFAULT_SPECS: dict[DjiKind, DjiSpec] = {
    DjiKind.C620: DjiSpec(
        DjiKind.C620,
        8,
        (CMD_ID_C6X0_1_4, CMD_ID_C6X0_5_8),
        FEEDBACK_BASE_C6X0,
        C620_RAW_LIMIT,
        C620_AMPS_PER_RAW,
        'A',
        C620_AMPS_PER_RAW,
        True,
    ),
    DjiKind.C610: DjiSpec(
        DjiKind.C610,
        8,
        (CMD_ID_C6X0_1_4, CMD_ID_C6X0_5_8),
        FEEDBACK_BASE_C6X0,
        C610_RAW_LIMIT,
        C610_AMPS_PER_RAW,
        'A',
        C610_AMPS_PER_RAW,
        False,
    ),
    DjiKind.GM6020_VOLTAGE: DjiSpec(
        DjiKind.GM6020_VOLTAGE,
        7,
        (CMD_ID_GM6020_VOLTAGE_1_4, CMD_ID_GM6020_VOLTAGE_5_7),
        FEEDBACK_BASE_GM6020,
        GM6020_VOLTAGE_RAW_LIMIT_SAFE,
        GM6020_VOLTS_PER_RAW,
        'V',
        GM6020_AMPS_PER_RAW_SAFE,
        True,
    ),
    DjiKind.GM6020_CURRENT: DjiSpec(
        DjiKind.GM6020_CURRENT,
        7,
        (CMD_ID_GM6020_CURRENT_1_4, CMD_ID_GM6020_CURRENT_5_7),
        FEEDBACK_BASE_GM6020,
        GM6020_CURRENT_RAW_LIMIT,
        GM6020_AMPS_PER_RAW_SAFE,
        'A',
        GM6020_AMPS_PER_RAW_SAFE,
        True,
    ),
}
_HARD_RAW_LIMITS = {
    DjiKind.C620: C620_RAW_LIMIT,
    DjiKind.C610: C610_RAW_LIMIT,
    DjiKind.GM6020_VOLTAGE: GM6020_VOLTAGE_RAW_LIMIT_MAX,
    DjiKind.GM6020_CURRENT: GM6020_CURRENT_RAW_LIMIT,
}
#: Default spec of every kind.
DJI_SPECS: dict[DjiKind, DjiSpec] = dict(_DEFAULT_SPECS)


def command_slot(kind: DjiKind | str, esc_id: int) -> tuple[int, int]:
    """Return ``(arbitration_id, slot)`` of the command frame for ``(kind, esc_id)``.

    Raises:
        HardwareConfigError: unknown kind.
        ValueRangeError: id out of range.
    """
    return make_dji_spec(kind).command_slot(esc_id)


def feedback_id(kind: DjiKind | str, esc_id: int) -> int:
    """Return the feedback frame id for ``(kind, esc_id)``.

    Raises:
        HardwareConfigError: unknown kind.
        ValueRangeError: id out of range.
    """
    return make_dji_spec(kind).feedback_id(esc_id)


def pack_command(raws: Sequence[int], limit: int | None = None) -> bytes:
    """Pack up to four raw commands into one 8-byte command frame (big-endian int16).

    Args:
        raws: raw values for slots 0.. (1 to 4 of them); missing slots are sent as 0.
        limit: reject values with ``abs(v) > limit``; None accepts the whole int16 range.

    Returns:
        8 data bytes.

    Raises:
        FrameLengthError: more than four values.
        ValueRangeError: a value is not an int or exceeds the limit / int16.
    """
    n = len(raws)
    if n > SLOTS_PER_FRAME:
        raise FrameLengthError(f'a DJI command frame has 4 slots, got {n} values')
    values = [0, 0, 0, 0]
    for i in range(n):
        v = raws[i]
        if isinstance(v, bool) or not isinstance(v, int):
            raise ValueRangeError(f'DJI command slot {i}: raw value must be an int, got {v!r}')
        if v > INT16_MAX or v < INT16_MIN:
            raise ValueRangeError(f'DJI command slot {i}: raw {v} outside int16')
        if limit is not None and (v > limit or v < -limit):
            raise ValueRangeError(f'DJI command slot {i}: raw {v} outside ±{limit}')
        values[i] = v
    return _COMMAND.pack(*values)


def unpack_command(data: bytes | bytearray) -> tuple[int, int, int, int]:
    """Unpack a command frame into its four raw slot values (device side).

    Raises:
        FrameLengthError: the frame is not 8 bytes.
    """
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'DJI command frame must be 8 bytes, got {len(data)}')
    return _COMMAND.unpack(data)


class DjiFeedback(NamedTuple):
    """One decoded feedback frame, in device units (the actuator converts to SI).

    Attributes:
        angle_ticks: rotor mechanical angle, 0..8191 (8192 per revolution).
        rotor_rpm: rotor speed [rpm], before any gearbox.
        current_raw: torque current, raw (see :attr:`DjiSpec.feedback_amps_per_raw`).
        temperature_c: [°C], or None for the C610.
    """

    angle_ticks: int
    rotor_rpm: int
    current_raw: int
    temperature_c: int | None


def decode_feedback(data: bytes | bytearray, has_temperature: bool = True) -> DjiFeedback:
    """Decode a feedback frame (host side).

    Args:
        data: 8 data bytes.
        has_temperature: False for the C610 (byte 6 is "Null").

    Returns:
        The decoded frame.

    Raises:
        FrameLengthError: not 8 bytes.
        ValueRangeError: angle above 8191.
    """
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'DJI feedback frame must be 8 bytes, got {len(data)}')
    angle, rpm, current, temperature = _FEEDBACK.unpack(data)
    if angle >= ENCODER_TICKS_PER_REV:
        raise ValueRangeError(f'DJI feedback angle {angle} outside 0..8191')
    return DjiFeedback(angle, rpm, current, temperature if has_temperature else None)


def encode_feedback(
    angle_ticks: int, rotor_rpm: int, current_raw: int, temperature_c: int | None = None
) -> bytes:
    """Encode a feedback frame (device side).

    Args:
        angle_ticks: 0..8191.
        rotor_rpm: int16 [rpm].
        current_raw: int16.
        temperature_c: 0..255 [°C]; None sends 0 (the C610's "Null").

    Returns:
        8 data bytes.

    Raises:
        ValueRangeError: a field outside its range.
    """
    if not 0 <= angle_ticks < ENCODER_TICKS_PER_REV:
        raise ValueRangeError(f'DJI feedback angle {angle_ticks} outside 0..8191')
    for name, v in (('rotor_rpm', rotor_rpm), ('current_raw', current_raw)):
        if not INT16_MIN <= v <= INT16_MAX:
            raise ValueRangeError(f'DJI feedback {name} {v} outside int16')
    temperature = 0 if temperature_c is None else temperature_c
    if not 0 <= temperature <= 0xFF:
        raise ValueRangeError(f'DJI feedback temperature {temperature} outside 0..255')
    return _FEEDBACK.pack(angle_ticks, rotor_rpm, current_raw, temperature)


def ticks_from_rad(rotor_angle: float) -> int:
    """Rotor angle [rad] (any value) to encoder ticks 0..8191, wrapped.

    Raises:
        ValueRangeError: angle is NaN or infinite.
    """
    if not math.isfinite(rotor_angle):
        raise ValueRangeError(f'rotor angle {rotor_angle!r} is not finite')
    return math.floor(rotor_angle / RAD_PER_TICK) % ENCODER_TICKS_PER_REV


def rpm_from_rad_per_s(rotor_velocity: float) -> int:
    """Rotor velocity [rad/s] to the rpm field, rounded and saturated to int16.

    Raises:
        ValueRangeError: velocity is NaN or infinite.
    """
    if not math.isfinite(rotor_velocity):
        raise ValueRangeError(f'rotor velocity {rotor_velocity!r} is not finite')
    rpm = round(rotor_velocity / RAD_PER_S_PER_RPM)
    return max(INT16_MIN, min(INT16_MAX, rpm))


def check_collisions(
    motors: Iterable[tuple[DjiKind | str, int]], names: Sequence[str] | None = None
) -> None:
    """Check that DJI motors on ONE bus use distinct command slots and feedback ids.

    A GM6020 with id n (1–4) uses the same 0x1FF slot and the same feedback id 0x204+n as
    a C620/C610 with id n+4; two motors of the same kind and id collide too.

    Args:
        motors: ``(kind, esc_id)`` of every DJI motor on the bus.
        names: optional labels (joint names) for the error message, same order.

    Raises:
        HardwareConfigError: two motors collide; the message names both.
        ValueRangeError: an id is out of range.
    """
    slots: dict[tuple[int, int], str] = {}
    feedback: dict[int, str] = {}
    for i, (kind, esc_id) in enumerate(motors):
        spec = make_dji_spec(kind)
        label = names[i] if names is not None else f'{spec.kind.value} id {esc_id}'
        slot = spec.command_slot(esc_id)
        fb = spec.feedback_id(esc_id)
        if slot in slots:
            raise HardwareConfigError(
                f'{label} and {slots[slot]} share command frame 0x{slot[0]:03X} slot {slot[1]}'
            )
        if fb in feedback:
            raise HardwareConfigError(f'{label} and {feedback[fb]} share feedback id 0x{fb:03X}')
        slots[slot] = label
        feedback[fb] = label
