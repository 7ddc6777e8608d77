"""LK-TECH (LingKong) MF/MG/MS motors' single-motor CAN protocol: bytes <-> values.

docs/PROTOCOLS.md §2.8. A request goes to 0x140 + id (id 1..32) and the motor answers
from the same id, echoing the command byte in byte 0. Every frame is 8 bytes, little
endian. The motion commands (torque 0xA1, speed 0xA2, positions 0xA3..0xA8) and the
status-2 read (0x9C) are answered with temperature, iq, speed and encoder; status 1
(0x9A, and clear-error 0x9B) with temperature, voltage, current, motor state and error
bits (the V2.35 layout); off, stop and run (0x80, 0x81, 0x88) are echoed.

The current scale differs by series and protocol version (:data:`CURRENT_SCALES`), the
encoder width by model: both are the joint's to set.
"""

from __future__ import annotations

import enum
import struct
from typing import NamedTuple

from rm_base.hardware.errors import FrameLengthError, ValueRangeError

FRAME_LENGTH = 8
#: Request and reply id of motor ``id``: BASE_ID + id.
BASE_ID = 0x140
MIN_MOTOR_ID = 1
MAX_MOTOR_ID = 32
#: The multi-motor torque frame (ids 1..4, enabled in LK's tool; not used by the robot).
MULTI_TORQUE_ID = 0x280
#: Speed command unit [deg/s per LSB], position command unit [deg per LSB].
CENTI = 0.01

_INT16 = struct.Struct('<h')
_INT32 = struct.Struct('<i')
_UINT16 = struct.Struct('<H')
_MOTION_REPLY = struct.Struct('<BbhhH')  # cmd, °C, iq, speed [dps], encoder
_STATUS_1 = struct.Struct('<BbHHBB')  # cmd, °C, voltage [0.01 V], current [0.01 A], state, error


class Command(enum.IntEnum):
    """Byte 0 of a request, echoed in its reply."""

    MOTOR_OFF = 0x80  # off: clears the turn count; the motor still answers
    STOP = 0x81  # no output, run state kept
    RUN = 0x88  # resume after off or stop
    READ_STATUS_1 = 0x9A
    CLEAR_ERROR = 0x9B  # answered like 0x9A; an error whose cause persists stays
    READ_STATUS_2 = 0x9C
    TORQUE = 0xA1
    SPEED = 0xA2
    MULTI_TURN = 0xA3
    MULTI_TURN_LIMITED = 0xA4
    SINGLE_TURN = 0xA5
    SINGLE_TURN_LIMITED = 0xA6
    INCREMENT = 0xA7
    INCREMENT_LIMITED = 0xA8


#: The commands with no payload (request bytes 1..7 are zero).
SIMPLE_COMMANDS = frozenset({
    Command.MOTOR_OFF, Command.STOP, Command.RUN, Command.READ_STATUS_1,
    Command.CLEAR_ERROR, Command.READ_STATUS_2,
})
#: Replies laid out as status 1 (voltage, state, error bits).
STATUS_REPLIES = frozenset({Command.READ_STATUS_1, Command.CLEAR_ERROR})
#: Replies laid out as status 2 (temperature, iq, speed, encoder).
MOTION_REPLIES = frozenset({
    Command.READ_STATUS_2, Command.TORQUE, Command.SPEED, Command.MULTI_TURN,
    Command.MULTI_TURN_LIMITED, Command.SINGLE_TURN, Command.SINGLE_TURN_LIMITED,
    Command.INCREMENT, Command.INCREMENT_LIMITED,
})
#: Replies that only echo the command.
ECHO_REPLIES = frozenset({Command.MOTOR_OFF, Command.STOP, Command.RUN})


class ErrorState(enum.IntFlag):
    """Status 1's error byte."""

    UNDER_VOLTAGE = 0x01
    OVER_TEMPERATURE = 0x08


def error_names(bits: int) -> str:
    """The error bits in words (``OVER_TEMPERATURE``, ``none``; unknown ones in hex)."""
    names = [flag.name or '' for flag in ErrorState if bits & flag]
    rest = bits & ~sum(ErrorState)
    if rest:
        names.append(f'0x{rest:02X}')
    return '|'.join(names) or 'none'


#: Status 1's motor-state byte (V2.35).
MOTOR_ON = 0x00
MOTOR_OFF = 0x10


class CurrentScale(NamedTuple):
    """How iq is counted: the command's range and amperes, and the replies' amperes.

    Attributes:
        command_limit: largest |iq| a torque command carries [LSB].
        command_amps: amperes per LSB of a command.
        reply_amps: amperes per LSB of a reply's iq.
    """

    command_limit: int
    command_amps: float
    reply_amps: float


#: V2.35: MF ±16.5 A and MG ±33 A over ±2048 both ways; V2.3: commands ±2000 = ±32 A,
#: replies ±2048 = ±33 A (docs/PROTOCOLS.md §2.8).
CURRENT_SCALES: dict[str, CurrentScale] = {
    'mf': CurrentScale(2048, 33.0 / 4096.0, 33.0 / 4096.0),
    'mg': CurrentScale(2048, 66.0 / 4096.0, 66.0 / 4096.0),
    'v2.3': CurrentScale(2000, 32.0 / 2000.0, 33.0 / 2048.0),
}
#: Encoder widths a model may have [bits] (18-bit encoders send their top 16).
ENCODER_BITS = (14, 15, 16)


class MotionReply(NamedTuple):
    """A reply to status 2 or to a motion command.

    Attributes:
        command: the echoed command byte.
        temperature_c: [°C].
        iq: torque current [LSB of the reply scale].
        speed_dps: rotor speed [deg/s].
        encoder: single-turn rotor position [ticks of the model's width].
    """

    command: int
    temperature_c: int
    iq: int
    speed_dps: int
    encoder: int


class Status1(NamedTuple):
    """A reply to status 1 or clear-error (V2.35 layout).

    Attributes:
        command: the echoed command byte.
        temperature_c: [°C].
        voltage_v: supply [V].
        current_a: bus current [A].
        motor_on: the motor state byte says on.
        error: :class:`ErrorState` bits (others kept as sent).
    """

    command: int
    temperature_c: int
    voltage_v: float
    current_a: float
    motor_on: bool
    error: int


def motor_frame_id(motor_id: int) -> int:
    """The request and reply id of a motor.

    Raises:
        ValueRangeError: id outside 1..32.
    """
    if not MIN_MOTOR_ID <= motor_id <= MAX_MOTOR_ID:
        raise ValueRangeError(f'LK motor id {motor_id} outside {MIN_MOTOR_ID}..{MAX_MOTOR_ID}')
    return BASE_ID + motor_id


def _frame(command: Command, d1: int = 0, d23: bytes = b'\x00\x00',
           d47: bytes = b'\x00\x00\x00\x00') -> bytes:
    return bytes((command, d1)) + d23 + d47


def _int32(name: str, value: int) -> bytes:
    try:
        return _INT32.pack(value)
    except struct.error as err:
        raise ValueRangeError(f'{name} {value} does not fit 32 bits') from err


def _uint16(name: str, value: int) -> bytes:
    if not 0 <= value <= 0xFFFF:
        raise ValueRangeError(f'{name} {value} outside 0..65535')
    return _UINT16.pack(value)


def pack_simple(command: Command | int) -> bytes:
    """A command with no payload (off, stop, run, the status reads, clear error).

    Raises:
        ValueRangeError: a command that takes a payload, or no command.
    """
    try:
        cmd = Command(command)
    except ValueError as err:
        raise ValueRangeError(f'0x{command:02X} is no LK command') from err
    if cmd not in SIMPLE_COMMANDS:
        raise ValueRangeError(f'{cmd.name} takes a payload')
    return _frame(cmd)


def pack_torque(iq: int, scale: CurrentScale) -> bytes:
    """0xA1: iq [LSB], saturated at the scale's command range."""
    iq = max(-scale.command_limit, min(scale.command_limit, iq))
    return _frame(Command.TORQUE, d47=_INT16.pack(iq) + b'\x00\x00')


def pack_speed(centi_dps: int) -> bytes:
    """0xA2: speed [0.01 deg/s]."""
    return _frame(Command.SPEED, d47=_int32('speed', centi_dps))


def pack_multi_turn(centi_deg: int, max_dps: int | None = None) -> bytes:
    """0xA3 (0xA4 with a speed limit [deg/s]): multi-turn angle [0.01 deg]."""
    angle = _int32('angle', centi_deg)
    if max_dps is None:
        return _frame(Command.MULTI_TURN, d47=angle)
    return _frame(Command.MULTI_TURN_LIMITED, d23=_uint16('max speed', max_dps), d47=angle)


def pack_single_turn(centi_deg: int, ccw: bool, max_dps: int | None = None) -> bytes:
    """0xA5 (0xA6 with a speed limit [deg/s]): turn to an angle in 0..35999 [0.01 deg].

    Bytes 4..7 carry it as V2.35's u32; V2.3 read only 4..5, which hold the same number
    for every angle in range.
    """
    if not 0 <= centi_deg <= 35999:
        raise ValueRangeError(f'single-turn angle {centi_deg} outside 0..35999')
    angle = _int32('angle', centi_deg)
    if max_dps is None:
        return _frame(Command.SINGLE_TURN, int(ccw), d47=angle)
    return _frame(Command.SINGLE_TURN_LIMITED, int(ccw), _uint16('max speed', max_dps), angle)


def pack_increment(centi_deg: int, max_dps: int | None = None) -> bytes:
    """0xA7 (0xA8 with a speed limit [deg/s]): turn by an angle [0.01 deg]."""
    angle = _int32('increment', centi_deg)
    if max_dps is None:
        return _frame(Command.INCREMENT, d47=angle)
    return _frame(Command.INCREMENT_LIMITED, d23=_uint16('max speed', max_dps), d47=angle)


def pack_multi_torque(iqs: tuple[int, int, int, int]) -> bytes:
    """0x280: iq [LSB, ±2000] of motors 1..4."""
    if len(iqs) != 4:
        raise ValueRangeError(f'0x280 carries 4 currents, got {len(iqs)}')
    return b''.join(_INT16.pack(max(-2000, min(2000, iq))) for iq in iqs)


def _checked(data: bytes | bytearray) -> int:
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'LK frame of {len(data)} bytes, expected {FRAME_LENGTH}')
    return data[0]


def decode_motion_reply(data: bytes | bytearray) -> MotionReply:
    """A reply to 0x9C or a motion command.

    Raises:
        FrameLengthError: not 8 bytes.
        ValueRangeError: byte 0 is not such a command.
    """
    if _checked(data) not in MOTION_REPLIES:
        raise ValueRangeError(f'0x{data[0]:02X} is no LK motion reply')
    return MotionReply(*_MOTION_REPLY.unpack(data))


def decode_status_1(data: bytes | bytearray) -> Status1:
    """A reply to 0x9A or 0x9B (V2.35: 0.01 V and 0.01 A).

    Raises:
        FrameLengthError: not 8 bytes.
        ValueRangeError: byte 0 is not 0x9A or 0x9B.
    """
    if _checked(data) not in STATUS_REPLIES:
        raise ValueRangeError(f'0x{data[0]:02X} is no LK status-1 reply')
    cmd, temperature, voltage, current, state, error = _STATUS_1.unpack(data)
    return Status1(cmd, temperature, voltage * 0.01, current * 0.01, state == MOTOR_ON, error)


def reply_command(data: bytes | bytearray) -> Command:
    """The command a reply echoes.

    Raises:
        FrameLengthError: not 8 bytes.
        ValueRangeError: byte 0 is no command of the protocol.
    """
    try:
        return Command(_checked(data))
    except ValueError as err:
        raise ValueRangeError(f'0x{data[0]:02X} is no LK command') from err


# -- the motor's side (the simulator) ---------------------------------------------------------

class Request(NamedTuple):
    """A request as the motor reads it.

    Attributes:
        command: the command byte.
        value: iq [LSB] (0xA1), speed [0.01 deg/s] (0xA2), angle or increment [0.01 deg]
            (0xA3..0xA8); 0 for the simple commands.
        max_dps: the speed limit of 0xA4/0xA6/0xA8 [deg/s], else None.
        ccw: 0xA5/0xA6's direction.
    """

    command: Command
    value: int
    max_dps: int | None
    ccw: bool


_LIMITED = frozenset({Command.MULTI_TURN_LIMITED, Command.SINGLE_TURN_LIMITED,
                      Command.INCREMENT_LIMITED})


def unpack_request(data: bytes | bytearray) -> Request:
    """What a request asks (the 0x140 + id frames).

    Raises:
        FrameLengthError: not 8 bytes.
        ValueRangeError: an unknown command byte.
    """
    cmd = reply_command(data)
    if cmd in SIMPLE_COMMANDS:
        return Request(cmd, 0, None, False)
    if cmd is Command.TORQUE:
        return Request(cmd, _INT16.unpack_from(data, 4)[0], None, False)
    max_dps = _UINT16.unpack_from(data, 2)[0] if cmd in _LIMITED else None
    return Request(cmd, _INT32.unpack_from(data, 4)[0], max_dps, bool(data[1]))


def encode_motion_reply(command: Command, temperature_c: int, iq: int, speed_dps: int,
                        encoder: int) -> bytes:
    """A motion reply, saturated to its fields (int8 °C, int16 iq and speed, u16 encoder)."""
    return _MOTION_REPLY.pack(
        command,
        max(-128, min(127, temperature_c)),
        max(-32768, min(32767, iq)),
        max(-32768, min(32767, speed_dps)),
        encoder & 0xFFFF,
    )


def encode_status_1(command: Command, temperature_c: int, voltage_v: float, current_a: float,
                    *, motor_on: bool, error: int) -> bytes:
    """A status-1 reply (V2.35 layout), saturated to its fields."""
    return _STATUS_1.pack(
        command,
        max(-128, min(127, temperature_c)),
        max(0, min(0xFFFF, round(voltage_v * 100.0))),
        max(0, min(0xFFFF, round(abs(current_a) * 100.0))),
        MOTOR_ON if motor_on else MOTOR_OFF,
        error & 0xFF,
    )
