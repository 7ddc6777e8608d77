"""Referee-system serial frames: the CRCs, the frame layout, and a resyncing parser.

docs/PROTOCOLS.md §6.1. Both referee links (the power-management module's user UART and
the image link) carry the same frames::

    A5 | len (u16 LE) | seq | CRC8(bytes 0..3) | cmd_id (u16 LE) | data[len] | CRC16 (LE)

CRC8 is the reflected 0x31 polynomial with init 0xFF, CRC16 the reflected 0x1021 with init
0xFFFF (CRC-16/MCRF4XX), both without a final xor, as DJI's own C code computes them.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

from rm_base.hardware.errors import ChecksumError, FrameLengthError

SOF = 0xA5
HEADER_LENGTH = 5  # SOF, length (2), seq, CRC8
CMD_ID_LENGTH = 2
CRC16_LENGTH = 2
#: Frame bytes beyond the data: header, cmd_id and CRC16.
OVERHEAD = HEADER_LENGTH + CMD_ID_LENGTH + CRC16_LENGTH
#: Largest data length accepted (the image link's 0x0310 carries 300 bytes).
MAX_DATA_LENGTH = 512

#: The 2025+ image-transmission module's remote frame: ``A9 53``, 17 payload bytes, CRC16.
REMOTE_HEADER = b'\xa9\x53'
REMOTE_FRAME_LENGTH = 21
#: The cmd_id a :class:`FrameParser` gives a remote frame (no referee command has it).
REMOTE_FRAME_ID = 0xA953

_LENGTH = struct.Struct('<H')


def _reflected_table(polynomial: int, width: int) -> tuple[int, ...]:
    """Byte table of a reflected CRC: ``crc = (crc >> 8) ^ table[(crc ^ byte) & 0xFF]``."""
    reflected = int(f'{polynomial:0{width}b}'[::-1], 2)
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ reflected if crc & 1 else crc >> 1
        table.append(crc)
    return tuple(table)


_CRC8_TABLE = _reflected_table(0x31, 8)
_CRC16_TABLE = _reflected_table(0x1021, 16)


def crc8(data: bytes, init: int = 0xFF) -> int:
    """The referee header CRC8 of data (check value of ``b'123456789'``: 0x0B)."""
    crc = init
    for byte in data:
        crc = _CRC8_TABLE[crc ^ byte]
    return crc


def crc16(data: bytes, init: int = 0xFFFF) -> int:
    """The referee frame CRC16 of data (check value of ``b'123456789'``: 0x6F91)."""
    crc = init
    for byte in data:
        crc = (crc >> 8) ^ _CRC16_TABLE[(crc ^ byte) & 0xFF]
    return crc


@dataclass(frozen=True)
class RawFrame:
    """One frame whose CRCs held: its command, its data bytes and its sequence number."""

    cmd_id: int
    data: bytes
    seq: int = 0


def encode_frame(cmd_id: int, data: bytes, seq: int = 0) -> bytes:
    """The complete frame carrying data as cmd_id.

    Raises:
        FrameLengthError: data longer than MAX_DATA_LENGTH.
        ValueError: cmd_id or seq out of range.
    """
    if len(data) > MAX_DATA_LENGTH:
        raise FrameLengthError(f'referee data of {len(data)} bytes > {MAX_DATA_LENGTH}')
    if not 0 <= cmd_id <= 0xFFFF or not 0 <= seq <= 0xFF:
        raise ValueError(f'cmd_id 0x{cmd_id:X} or seq {seq} out of range')
    header = bytes((SOF, *_LENGTH.pack(len(data)), seq))
    body = header + bytes((crc8(header),)) + struct.pack('<H', cmd_id) + bytes(data)
    return body + struct.pack('<H', crc16(body))


def decode_frame(frame: bytes) -> RawFrame:
    """Check and split one complete frame (the inverse of :func:`encode_frame`).

    Raises:
        FrameLengthError: not a whole frame (too short, or its length field disagrees).
        ChecksumError: the CRC8 or the CRC16 does not hold.
    """
    if len(frame) < OVERHEAD or frame[0] != SOF:
        raise FrameLengthError(f'not a referee frame: {bytes(frame[:8]).hex(" ")}')
    (length,) = _LENGTH.unpack_from(frame, 1)
    if len(frame) != length + OVERHEAD:
        raise FrameLengthError(f'frame of {len(frame)} bytes says {length} data bytes')
    if crc8(frame[:4]) != frame[4]:
        raise ChecksumError('referee header CRC8 mismatch')
    if crc16(frame[:-2]) != _LENGTH.unpack_from(frame, len(frame) - 2)[0]:
        raise ChecksumError('referee frame CRC16 mismatch')
    (cmd_id,) = _LENGTH.unpack_from(frame, HEADER_LENGTH)
    return RawFrame(cmd_id, bytes(frame[HEADER_LENGTH + CMD_ID_LENGTH : -CRC16_LENGTH]), frame[3])


@dataclass
class ParserStats:
    """What the parser threw away (all counts since it was made)."""

    frames: int = 0
    header_errors: int = 0  # CRC8 failed or the length is beyond MAX_DATA_LENGTH
    crc_errors: int = 0  # CRC16 failed
    skipped_bytes: int = 0  # bytes before a start of frame that led to a good frame or none


@dataclass
class FrameParser:
    """Turns a byte stream into frames; any split of the stream gives the same frames.

    A bad header or a bad CRC16 resyncs at the byte after that frame's start, so a frame
    that starts inside a damaged one is still found. With ``image_link`` the parser also
    takes the image-transmission module's ``A9 53`` remote frames (their CRC16 over the
    first 19 bytes), given as ``RawFrame(REMOTE_FRAME_ID, <the 17 payload bytes>)``.
    """

    image_link: bool = False
    stats: ParserStats = field(default_factory=ParserStats)
    _buffer: bytearray = field(default_factory=bytearray)

    # The counters a serial reader reports for any device's parser.
    @property
    def frames_ok(self) -> int:
        """Frames whose CRCs held."""
        return self.stats.frames

    @property
    def crc_errors(self) -> int:
        """Frames whose CRC16 failed."""
        return self.stats.crc_errors

    @property
    def length_errors(self) -> int:
        """Headers that failed (CRC8, or a length beyond MAX_DATA_LENGTH)."""
        return self.stats.header_errors

    @property
    def decode_errors(self) -> int:
        """Always 0: the parser only frames; decoding comes after (``StatusDecoder``)."""
        return 0

    @property
    def bytes_discarded(self) -> int:
        """Bytes skipped while looking for a frame."""
        return self.stats.skipped_bytes

    def feed(self, data: bytes) -> list[RawFrame]:
        """Add received bytes; return every frame completed by them, in order."""
        buffer = self._buffer
        buffer += data
        frames: list[RawFrame] = []
        start = 0
        while True:
            found = self._next_start(buffer, start)
            self.stats.skipped_bytes += found - start
            start = found
            if start == len(buffer):
                break
            if buffer[start] == SOF:
                frame, size = self._referee_frame(buffer, start)
            else:
                frame, size = self._remote_frame(buffer, start)
            if size == 0:
                break  # wait for more bytes
            if frame is None:
                start += 1  # resync after this start byte
                continue
            frames.append(frame)
            self.stats.frames += 1
            start += size
        del buffer[:start]
        return frames

    def _next_start(self, buffer: bytearray, start: int) -> int:
        sof = buffer.find(SOF, start)
        sof = len(buffer) if sof < 0 else sof
        if self.image_link:
            remote = buffer.find(REMOTE_HEADER[0], start, sof)
            if remote >= 0:
                return remote
        return sof

    def _referee_frame(self, buffer: bytearray, start: int) -> tuple[RawFrame | None, int]:
        """(frame or None if bad, its size); size 0: not all of it has arrived."""
        if len(buffer) - start < HEADER_LENGTH:
            return None, 0
        (length,) = _LENGTH.unpack_from(buffer, start + 1)
        if length > MAX_DATA_LENGTH or crc8(buffer[start : start + 4]) != buffer[start + 4]:
            self.stats.header_errors += 1
            return None, 1
        size = length + OVERHEAD
        if len(buffer) - start < size:
            return None, 0
        end = start + size
        if crc16(buffer[start : end - CRC16_LENGTH]) != _LENGTH.unpack_from(buffer, end - 2)[0]:
            self.stats.crc_errors += 1
            return None, 1
        (cmd_id,) = _LENGTH.unpack_from(buffer, start + HEADER_LENGTH)
        data = bytes(buffer[start + HEADER_LENGTH + CMD_ID_LENGTH : end - CRC16_LENGTH])
        return RawFrame(cmd_id, data, buffer[start + 3]), size

    def _remote_frame(self, buffer: bytearray, start: int) -> tuple[RawFrame | None, int]:
        if len(buffer) - start < 2:
            return None, 0
        if buffer[start + 1] != REMOTE_HEADER[1]:
            return None, 1  # an A9 that starts nothing
        if len(buffer) - start < REMOTE_FRAME_LENGTH:
            return None, 0
        end = start + REMOTE_FRAME_LENGTH
        if crc16(buffer[start : end - 2]) != _LENGTH.unpack_from(buffer, end - 2)[0]:
            self.stats.crc_errors += 1
            return None, 1
        return RawFrame(REMOTE_FRAME_ID, bytes(buffer[start + 2 : end - 2])), REMOTE_FRAME_LENGTH
