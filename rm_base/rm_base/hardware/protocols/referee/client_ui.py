"""What the robot sends on the referee link: 0x0301 interaction data and client UI figures.

docs/PROTOCOLS.md §6.4. A 0x0301 frame's data is a 6-byte sub-header (content id, sender
robot id, receiver id) and the content (at most 112 bytes); the whole 0x0301 traffic of a
robot may be at most 30 Hz. UI figures go to the robot's own client, id 0x0100 + robot id.
A figure is 15 bytes of bit fields; the screen is 1920 x 1080 with (0, 0) bottom left.
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Sequence
from dataclasses import dataclass

from rm_base.hardware.errors import ValueRangeError

INTERACTION_CMD_ID = 0x0301
MAX_CONTENT_LENGTH = 112
#: Bytes of a frame besides its data: header 5, cmd id 2, CRC16 2.
FRAME_OVERHEAD = 9
#: The rules' limits on a robot's 0x0301 traffic: bytes (whole frames) and frames a second.
MAX_BYTES_PER_S = 3720
MAX_FRAMES_PER_S = 30
CLIENT_ID_BASE = 0x0100
SERVER_ID = 0x8080
DELETE_FIGURES = 0x0100
DRAW_TEXT = 0x0110
TEXT_LENGTH = 30
#: Figures per drawing command: 0x0101 draws 1, 0x0102 2, 0x0103 5, 0x0104 7.
DRAW_COMMANDS = ((1, 0x0101), (2, 0x0102), (5, 0x0103), (7, 0x0104))
FIGURE_LENGTH = 15
SCREEN_WIDTH, SCREEN_HEIGHT = 1920, 1080

_SUB_HEADER = struct.Struct('<HHH')


class FigureOp(enum.IntEnum):
    """What to do with a figure (by its name)."""

    NONE = 0
    ADD = 1
    MODIFY = 2
    DELETE = 3


class FigureType(enum.IntEnum):
    """The figure's shape."""

    LINE = 0
    RECTANGLE = 1
    CIRCLE = 2
    ELLIPSE = 3
    ARC = 4
    FLOAT = 5
    INTEGER = 6
    TEXT = 7


class Color(enum.IntEnum):
    """Figure colours (TEAM: the robot's own red or blue)."""

    TEAM = 0
    YELLOW = 1
    GREEN = 2
    ORANGE = 3
    PURPLE_RED = 4
    PINK = 5
    CYAN = 6
    BLACK = 7
    WHITE = 8


class DeleteOp(enum.IntEnum):
    """0x0100's operation."""

    NONE = 0
    LAYER = 1
    ALL = 2


@dataclass(frozen=True)
class Figure:
    """One client UI figure, its fields as the protocol names them.

    What details_a..e mean depends on the type: line and rectangle: (d, e) the end point
    or opposite corner; circle: c the radius; ellipse: (d, e) the semi-axes; arc: a, b the
    start and end angle [deg, 0 at 12 o'clock, clockwise] and (d, e) the semi-axes; float
    and integer: a the font size, the value in c|d|e (see :func:`number`); text: a the font
    size, b the length.
    """

    name: bytes
    op: FigureOp
    type: FigureType
    layer: int
    color: Color
    x: int
    y: int
    width: int = 1
    details_a: int = 0
    details_b: int = 0
    details_c: int = 0
    details_d: int = 0
    details_e: int = 0


def line(
    name: bytes, start: tuple[int, int], end: tuple[int, int], *, layer: int = 0,
    color: Color = Color.TEAM, width: int = 2, op: FigureOp = FigureOp.ADD,
) -> Figure:
    """A straight line from start to end [px]."""
    return Figure(name, op, FigureType.LINE, layer, color, start[0], start[1], width,
                  details_d=end[0], details_e=end[1])


def circle(
    name: bytes, centre: tuple[int, int], radius: int, *, layer: int = 0,
    color: Color = Color.TEAM, width: int = 2, op: FigureOp = FigureOp.ADD,
) -> Figure:
    """A circle around centre [px]."""
    return Figure(name, op, FigureType.CIRCLE, layer, color, centre[0], centre[1], width,
                  details_c=radius)


def rectangle(
    name: bytes, corner: tuple[int, int], opposite: tuple[int, int], *, layer: int = 0,
    color: Color = Color.TEAM, width: int = 2, op: FigureOp = FigureOp.ADD,
) -> Figure:
    """A rectangle's outline between two opposite corners [px]."""
    return Figure(name, op, FigureType.RECTANGLE, layer, color, corner[0], corner[1], width,
                  details_d=opposite[0], details_e=opposite[1])


def integer(
    name: bytes, at: tuple[int, int], value: int, *, font_size: int = 20, layer: int = 0,
    color: Color = Color.TEAM, width: int = 2, op: FigureOp = FigureOp.ADD,
) -> Figure:
    """A whole number (an int32 in details c|d|e)."""
    raw = int(value) & 0xFFFFFFFF
    return Figure(name, op, FigureType.INTEGER, layer, color, at[0], at[1], width,
                  details_a=font_size, details_c=raw & 0x3FF, details_d=(raw >> 10) & 0x7FF,
                  details_e=raw >> 21)


def number(
    name: bytes, at: tuple[int, int], value: float, *, font_size: int = 20, layer: int = 0,
    color: Color = Color.TEAM, width: int = 2, op: FigureOp = FigureOp.ADD,
) -> Figure:
    """A float shown with three decimals (the client shows the int32 / 1000)."""
    raw = round(value * 1000) & 0xFFFFFFFF
    return Figure(name, op, FigureType.FLOAT, layer, color, at[0], at[1], width,
                  details_a=font_size, details_c=raw & 0x3FF, details_d=(raw >> 10) & 0x7FF,
                  details_e=raw >> 21)


def text_figure(
    name: bytes, at: tuple[int, int], length: int, *, font_size: int = 20, layer: int = 0,
    color: Color = Color.TEAM, width: int = 2, op: FigureOp = FigureOp.ADD,
) -> Figure:
    """The figure of a text of length characters (its characters go in :func:`draw_text`)."""
    return Figure(name, op, FigureType.TEXT, layer, color, at[0], at[1], width,
                  details_a=font_size, details_b=length)


def text_drawing(figure: Figure, text: str) -> tuple[int, bytes]:
    """(content id, content) of one text figure: 0x0110, the figure, 30 bytes of text.

    Raises:
        ValueRangeError: not a text figure, a text of more than 30 ASCII characters, or a
            figure that does not encode.
    """
    if figure.type is not FigureType.TEXT:
        raise ValueRangeError(f'figure {figure.name!r} is a {figure.type.name}, not a TEXT')
    try:
        chars = text.encode('ascii')
    except UnicodeEncodeError:
        raise ValueRangeError(f'text {text!r} is not ASCII') from None
    if len(chars) > TEXT_LENGTH:
        raise ValueRangeError(f'text of {len(chars)} characters > {TEXT_LENGTH}')
    return DRAW_TEXT, encode_figure(figure) + chars.ljust(TEXT_LENGTH, b'\0')


def draw_text(robot_id: int, figure: Figure, text: str) -> bytes:
    """The 0x0301 data of one text figure on the robot's client (see :func:`text_drawing`)."""
    content_id, content = text_drawing(figure, text)
    return interaction(content_id, robot_id, client_id(robot_id), content)


_FIELD_BITS = (
    ('layer', 4), ('color', 4), ('details_a', 9), ('details_b', 9), ('width', 10),
    ('x', 11), ('y', 11), ('details_c', 10), ('details_d', 11), ('details_e', 11),
)


def encode_figure(figure: Figure) -> bytes:
    """The 15 bytes of one figure.

    Raises:
        ValueRangeError: a name that is not 3 bytes, or a field too wide for its bits.
    """
    if len(figure.name) != 3:
        raise ValueRangeError(f'figure name must be 3 bytes, got {figure.name!r}')
    if not 0 <= figure.layer <= 9:
        raise ValueRangeError(f'figure {figure.name!r}: layer must be 0..9, got {figure.layer}')
    for key, bits in _FIELD_BITS:
        value = int(getattr(figure, key))
        if not 0 <= value < 1 << bits:
            raise ValueRangeError(f'figure {figure.name!r}: {key} {value} does not fit {bits} bits')
    f = figure
    word1 = (int(f.op) | int(f.type) << 3 | f.layer << 6 | int(f.color) << 10
             | f.details_a << 14 | f.details_b << 23)
    word2 = f.width | f.x << 10 | f.y << 21
    word3 = f.details_c | f.details_d << 10 | f.details_e << 21
    return bytes(f.name) + struct.pack('<III', word1, word2, word3)


def client_id(robot_id: int) -> int:
    """The id of a robot's own operator client."""
    return CLIENT_ID_BASE + robot_id


def interaction(content_id: int, sender_id: int, receiver_id: int, content: bytes) -> bytes:
    """The data of one 0x0301 frame.

    Raises:
        ValueRangeError: content longer than 112 bytes, or an id beyond 16 bits.
    """
    if len(content) > MAX_CONTENT_LENGTH:
        raise ValueRangeError(f'0x0301 content of {len(content)} bytes > {MAX_CONTENT_LENGTH}')
    for name, value in (('content id', content_id), ('sender', sender_id),
                        ('receiver', receiver_id)):
        if not 0 <= value <= 0xFFFF:
            raise ValueRangeError(f'0x0301 {name} {value} out of range')
    return _SUB_HEADER.pack(content_id, sender_id, receiver_id) + bytes(content)


def drawing(figures: Sequence[Figure]) -> tuple[int, bytes]:
    """(content id, content) drawing up to 7 figures (padded with no-op figures).

    Raises:
        ValueRangeError: no figure or more than 7, or a figure that does not encode.
    """
    count = len(figures)
    slots = next((n, cmd) for n, cmd in DRAW_COMMANDS if n >= count) if 0 < count <= 7 else None
    if slots is None:
        raise ValueRangeError(f'a drawing command carries 1 to 7 figures, got {count}')
    size, content_id = slots
    content = b''.join(encode_figure(f) for f in figures) + bytes(FIGURE_LENGTH * (size - count))
    return content_id, content


def draw(robot_id: int, figures: Sequence[Figure]) -> bytes:
    """The 0x0301 data drawing up to 7 figures on the robot's client (see :func:`drawing`)."""
    content_id, content = drawing(figures)
    return interaction(content_id, robot_id, client_id(robot_id), content)


def deletion(op: DeleteOp, layer: int = 0) -> tuple[int, bytes]:
    """(content id, content) deleting one layer (0-9) or every figure."""
    if not 0 <= layer <= 9:
        raise ValueRangeError(f'UI layer must be 0..9, got {layer}')
    return DELETE_FIGURES, bytes((op, layer))


def delete(robot_id: int, op: DeleteOp, layer: int = 0) -> bytes:
    """The 0x0301 data deleting one layer (0-9) or every figure of the robot's client."""
    content_id, content = deletion(op, layer)
    return interaction(content_id, robot_id, client_id(robot_id), content)


def decode_figure(data: bytes) -> Figure:
    """One figure from its 15 bytes (the inverse of :func:`encode_figure`).

    Raises:
        ValueRangeError: not 15 bytes, or an operation, type or colour that does not exist.
    """
    if len(data) != FIGURE_LENGTH:
        raise ValueRangeError(f'a figure is {FIGURE_LENGTH} bytes, got {len(data)}')
    word1, word2, word3 = struct.unpack('<III', data[3:])
    try:
        op, kind, color = FigureOp(word1 & 7), FigureType(word1 >> 3 & 7), Color(word1 >> 10 & 15)
    except ValueError as err:
        raise ValueRangeError(f'figure {bytes(data[:3])!r}: {err}') from None
    return Figure(
        bytes(data[:3]), op, kind, word1 >> 6 & 15, color, word2 >> 10 & 0x7FF,
        word2 >> 21, word2 & 0x3FF, word1 >> 14 & 0x1FF, word1 >> 23, word3 & 0x3FF,
        word3 >> 10 & 0x7FF, word3 >> 21,
    )


@dataclass(frozen=True)
class Interaction:
    """One 0x0301 frame's data, as the referee reads it."""

    content_id: int
    sender_id: int
    receiver_id: int
    content: bytes


def decode_interaction(data: bytes) -> Interaction:
    """The sub-header and content of 0x0301 data.

    Raises:
        ValueRangeError: shorter than the sub-header, or content beyond 112 bytes.
    """
    if not _SUB_HEADER.size <= len(data) <= _SUB_HEADER.size + MAX_CONTENT_LENGTH:
        raise ValueRangeError(f'0x0301 data of {len(data)} bytes')
    content_id, sender, receiver = _SUB_HEADER.unpack_from(data)
    return Interaction(content_id, sender, receiver, bytes(data[_SUB_HEADER.size:]))


def decode_drawing(content_id: int, content: bytes) -> tuple[list[Figure], str | None]:
    """The figures of a drawing command (0x0101-0x0104, 0x0110) and a text's characters.

    No-op figures (padding) are left out.

    Raises:
        ValueRangeError: not a drawing command, or content of the wrong length.
    """
    if content_id == DRAW_TEXT:
        if len(content) != FIGURE_LENGTH + TEXT_LENGTH:
            raise ValueRangeError(f'0x0110 content of {len(content)} bytes')
        chars = content[FIGURE_LENGTH:].rstrip(b'\0').decode('ascii', 'replace')
        return [decode_figure(content[:FIGURE_LENGTH])], chars
    size = next((n for n, cmd in DRAW_COMMANDS if cmd == content_id), None)
    if size is None:
        raise ValueRangeError(f'0x{content_id:04X} is not a drawing command')
    if len(content) != size * FIGURE_LENGTH:
        raise ValueRangeError(f'0x{content_id:04X} content of {len(content)} bytes')
    figures = [decode_figure(content[i:i + FIGURE_LENGTH])
               for i in range(0, len(content), FIGURE_LENGTH)]
    return [f for f in figures if f.op is not FigureOp.NONE], None
