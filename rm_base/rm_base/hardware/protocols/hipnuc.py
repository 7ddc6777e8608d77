"""HiPNUC IMU serial protocol (HI220 / HI221 / HI226 ...): framing, 0x91 and legacy items.

Why one module: framing, CRC and every data item the vendor's decoder reads (0x91 and the
legacy items).

docs/PROTOCOLS.md §4. A frame is::

    5A A5 | LEN (uint16 LE, payload only) | CRC16 (uint16 LE) | payload (LEN bytes)

with CRC-16/XMODEM (poly 0x1021, init 0, no reflection) over the 4 header bytes before
the CRC and then the payload. The payload is a sequence of items, each starting with a
tag byte: 0x91 (IMUSOL, 76 bytes, floats) or the legacy int16 items of older HI226/HI229
firmware (0x90 id, 0xA0/0xA1 acc, 0xB0/0xB1 gyro, 0xC0 mag, 0xD0 euler, 0xD1 quaternion,
0xF0 pressure). Which one a given unit sends depends on its firmware (UNVERIFIED), so the
decoder accepts both.

Everything decoded is SI (except the magnetic field, kept in µT as the device reports it):
acceleration m/s² (the device sends g; ×9.80665), angular rate rad/s (device: deg/s),
Euler angles rad as ``(roll, pitch, yaw)`` (device: deg), quaternion ``(w, x, y, z)``.
The legacy 0xC0 magnetometer unit is not stated in HiPNUC's code (UNVERIFIED; assumed µT).

The CRC is :func:`binascii.crc_hqx` from the standard library, which is CRC-16/XMODEM
when started from 0.
"""

from __future__ import annotations

import binascii
import dataclasses
import math
import struct

from rm_base.hardware.errors import (
    ChecksumError,
    FrameLengthError,
    ProtocolError,
    ValueRangeError,
)

SYNC = b'\x5a\xa5'
HEADER_LENGTH = 6
#: Largest raw frame HiPNUC's decoder accepts (hipnuc_dec.h); payload at most 506 bytes.
MAX_FRAME_LENGTH = 512
MAX_PAYLOAD_LENGTH = MAX_FRAME_LENGTH - HEADER_LENGTH
#: Standard gravity [m/s²] (HiPNUC's Python parser; its C examples use 9.8).
STANDARD_GRAVITY = 9.80665
DEG_TO_RAD = math.pi / 180.0

TAG_USER_ID = 0x90
TAG_IMUSOL = 0x91
TAG_INSSOL = 0x81
TAG_ACC_RAW = 0xA0
TAG_ACC_CAL = 0xA1
TAG_GYR_RAW = 0xB0
TAG_GYR_CAL = 0xB1
TAG_MAG_RAW = 0xC0
TAG_EULER = 0xD0
TAG_QUAT = 0xD1
TAG_PRESSURE = 0xF0

#: Legacy scales: acc int16 / 1000 → g, gyro / 10 → deg/s, mag / 10 → µT (assumed),
#: euler pitch and roll / 100, yaw / 10 → deg.
LEGACY_ACC_PER_G = 1000.0
LEGACY_GYR_PER_DEG_S = 10.0
LEGACY_MAG_PER_UT = 10.0
LEGACY_PITCH_ROLL_PER_DEG = 100.0
LEGACY_YAW_PER_DEG = 10.0

_HEADER = struct.Struct('<2sHH')
_IMUSOL = struct.Struct('<BHbfI3f3f3f3f4f')  # 76 bytes
_U8 = struct.Struct('<B')
_I16X3 = struct.Struct('<3h')
_F32 = struct.Struct('<f')
_F32X4 = struct.Struct('<4f')
#: Item lengths including the tag byte.
ITEM_LENGTHS = {
    TAG_USER_ID: 2,
    TAG_IMUSOL: _IMUSOL.size,
    TAG_INSSOL: 104,  # known, not decoded here
    TAG_ACC_RAW: 7,
    TAG_ACC_CAL: 7,
    TAG_GYR_RAW: 7,
    TAG_GYR_CAL: 7,
    TAG_MAG_RAW: 7,
    TAG_EULER: 7,
    TAG_QUAT: 17,
    TAG_PRESSURE: 5,
}

Vector3 = tuple[float, float, float]


def crc16_xmodem(data: bytes | bytearray, crc: int = 0) -> int:
    """CRC-16/XMODEM of ``data`` continuing from ``crc`` (``crc16(b'123456789') == 0x31C3``)."""
    return binascii.crc_hqx(data, crc)


def frame_crc(frame: bytes | bytearray) -> int:
    """CRC of a frame: header bytes 0..3, then the payload (bytes 6..)."""
    return binascii.crc_hqx(frame[HEADER_LENGTH:], binascii.crc_hqx(frame[:4], 0))


def encode_frame(payload: bytes | bytearray) -> bytes:
    """Wrap ``payload`` into a frame (sync, length, CRC).

    Raises:
        FrameLengthError: empty or longer than 506 bytes.
    """
    n = len(payload)
    if not 0 < n <= MAX_PAYLOAD_LENGTH:
        raise FrameLengthError(f'HiPNUC payload length {n} outside 1..{MAX_PAYLOAD_LENGTH}')
    head = SYNC + n.to_bytes(2, 'little')
    crc = binascii.crc_hqx(payload, binascii.crc_hqx(head, 0))
    return head + crc.to_bytes(2, 'little') + bytes(payload)


def decode_frame(frame: bytes | bytearray) -> bytes:
    """Check one complete frame and return its payload.

    Raises:
        FrameLengthError: shorter than a header, or LEN does not match the frame.
        ProtocolError: wrong sync bytes.
        ChecksumError: CRC mismatch.
    """
    if len(frame) < HEADER_LENGTH:
        raise FrameLengthError(f'HiPNUC frame of {len(frame)} bytes is shorter than its header')
    sync, length, crc = _HEADER.unpack_from(frame)
    if sync != SYNC:
        raise ProtocolError(f'HiPNUC frame starts with {sync.hex(" ")}, expected 5a a5')
    if length != len(frame) - HEADER_LENGTH:
        raise FrameLengthError(
            f'HiPNUC LEN {length} does not match the {len(frame) - HEADER_LENGTH}-byte payload'
        )
    computed = frame_crc(frame)
    if computed != crc:
        raise ChecksumError(f'HiPNUC CRC 0x{crc:04X} in frame, computed 0x{computed:04X}')
    return bytes(frame[HEADER_LENGTH:])


@dataclasses.dataclass(frozen=True)
class ImuSample:
    """What one frame carried; fields the frame did not carry are None.

    Attributes:
        acc: linear acceleration (x, y, z) [m/s²], sensor frame.
        gyr: angular rate (x, y, z) [rad/s].
        mag: magnetic field (x, y, z) [µT].
        euler: (roll, pitch, yaw) [rad].
        quat: orientation quaternion (w, x, y, z).
        temperature: [°C].
        pressure: air pressure [Pa].
        system_time_ms: device time [ms] (0x91).
        status: main_status (0x91).
        user_id: user id (0x90).
        skipped_tags: items recognised but not decoded (e.g. 0x81).
        unread_tag: the first item of unknown length (e.g. 0x83); it and the rest of the
            payload were not read, the items before it were.
    """

    acc: Vector3 | None = None
    gyr: Vector3 | None = None
    mag: Vector3 | None = None
    euler: Vector3 | None = None
    quat: tuple[float, float, float, float] | None = None
    temperature: float | None = None
    pressure: float | None = None
    system_time_ms: int | None = None
    status: int | None = None
    user_id: int | None = None
    skipped_tags: tuple[int, ...] = ()
    unread_tag: int | None = None


def decode_payload(payload: bytes | bytearray) -> ImuSample:
    """Decode the items of a payload into one :class:`ImuSample` (SI units).

    Later items overwrite earlier ones of the same kind, as in HiPNUC's decoder. An item
    of unknown length (0x83, whose layout is not in docs/PROTOCOLS.md) ends the reading:
    the items before it are kept and the sample names it in ``unread_tag``, so a unit that
    sends 0x91 followed by 0x83 still gives its 0x91 every frame.

    Raises:
        FrameLengthError: an item runs past the end of the payload.
        ProtocolError: the payload starts with an unknown item tag (nothing to keep).
    """
    f: dict[str, object] = {}
    skipped: list[int] = []
    ofs = 0
    n = len(payload)
    while ofs < n:
        tag = payload[ofs]
        size = ITEM_LENGTHS.get(tag)
        if size is None:
            if ofs == 0:
                raise ProtocolError(f'unknown HiPNUC item tag 0x{tag:02X} at payload offset 0')
            f['unread_tag'] = tag
            break
        if ofs + size > n:
            raise FrameLengthError(
                f'HiPNUC item 0x{tag:02X} needs {size} bytes, {n - ofs} left in the payload'
            )
        body = ofs + 1
        if tag == TAG_IMUSOL:
            v = _IMUSOL.unpack_from(payload, ofs)
            f['status'], f['temperature'], f['pressure'], f['system_time_ms'] = v[1:5]
            f['acc'] = (v[5] * STANDARD_GRAVITY, v[6] * STANDARD_GRAVITY, v[7] * STANDARD_GRAVITY)
            f['gyr'] = (v[8] * DEG_TO_RAD, v[9] * DEG_TO_RAD, v[10] * DEG_TO_RAD)
            f['mag'] = v[11:14]
            f['euler'] = (v[14] * DEG_TO_RAD, v[15] * DEG_TO_RAD, v[16] * DEG_TO_RAD)
            f['quat'] = v[17:21]
        elif tag == TAG_USER_ID:
            f['user_id'] = payload[body]
        elif tag in (TAG_ACC_RAW, TAG_ACC_CAL):
            k = STANDARD_GRAVITY / LEGACY_ACC_PER_G
            x, y, z = _I16X3.unpack_from(payload, body)
            f['acc'] = (x * k, y * k, z * k)
        elif tag in (TAG_GYR_RAW, TAG_GYR_CAL):
            k = DEG_TO_RAD / LEGACY_GYR_PER_DEG_S
            x, y, z = _I16X3.unpack_from(payload, body)
            f['gyr'] = (x * k, y * k, z * k)
        elif tag == TAG_MAG_RAW:
            x, y, z = _I16X3.unpack_from(payload, body)
            f['mag'] = (x / LEGACY_MAG_PER_UT, y / LEGACY_MAG_PER_UT, z / LEGACY_MAG_PER_UT)
        elif tag == TAG_EULER:
            pitch, roll, yaw = _I16X3.unpack_from(payload, body)
            f['euler'] = (
                roll / LEGACY_PITCH_ROLL_PER_DEG * DEG_TO_RAD,
                pitch / LEGACY_PITCH_ROLL_PER_DEG * DEG_TO_RAD,
                yaw / LEGACY_YAW_PER_DEG * DEG_TO_RAD,
            )
        elif tag == TAG_QUAT:
            f['quat'] = _F32X4.unpack_from(payload, body)
        elif tag == TAG_PRESSURE:
            f['pressure'] = _F32.unpack_from(payload, body)[0]
        else:
            skipped.append(tag)
        ofs += size
    return ImuSample(**f, skipped_tags=tuple(skipped))  # type: ignore[arg-type]


def _finite3(name: str, v: tuple[float, ...], n: int = 3) -> tuple[float, ...]:
    if len(v) != n or not all(math.isfinite(x) for x in v):
        raise ValueRangeError(f'HiPNUC {name} must be {n} finite numbers, got {v!r}')
    return v


def encode_imusol(
    *,
    acc: Vector3,
    gyr: Vector3,
    mag: Vector3,
    euler: Vector3,
    quat: tuple[float, float, float, float],
    temperature: int = 25,
    pressure: float = 101325.0,
    system_time_ms: int = 0,
    status: int = 0,
) -> bytes:
    """Encode one 0x91 IMUSOL item (76 bytes; wrap it with :func:`encode_frame`).

    Args:
        acc: [m/s²] (sent in g).
        gyr: [rad/s] (sent in deg/s).
        mag: [µT].
        euler: (roll, pitch, yaw) [rad] (sent in deg).
        quat: (w, x, y, z).
        temperature: [°C], int8.
        pressure: [Pa].
        system_time_ms: uint32 [ms].
        status: main_status, uint16.

    Raises:
        ValueRangeError: a value is not finite or does not fit its field.
    """
    ax, ay, az = _finite3('acc', acc)
    gx, gy, gz = _finite3('gyr', gyr)
    _finite3('mag', mag)
    roll, pitch, yaw = _finite3('euler', euler)
    _finite3('quat', quat, 4)
    if not (
        -128 <= temperature <= 127
        and 0 <= status <= 0xFFFF
        and 0 <= system_time_ms <= 0xFFFFFFFF
        and math.isfinite(pressure)
    ):
        raise ValueRangeError(
            f'HiPNUC 0x91 temperature {temperature}, status {status}, time {system_time_ms} '
            f'or pressure {pressure} out of range'
        )
    g = STANDARD_GRAVITY
    r2d = 1.0 / DEG_TO_RAD
    try:
        return _IMUSOL.pack(
            TAG_IMUSOL,
            status,
            temperature,
            pressure,
            system_time_ms,
            ax / g,
            ay / g,
            az / g,
            gx * r2d,
            gy * r2d,
            gz * r2d,
            *mag,
            roll * r2d,
            pitch * r2d,
            yaw * r2d,
            *quat,
        )
    except (struct.error, OverflowError) as err:
        raise ValueRangeError(f'HiPNUC 0x91 value does not fit a float32: {err}') from err


def _i16x3(name: str, values: tuple[float, ...], scales: tuple[float, float, float]) -> bytes:
    raws = [round(v * s) for v, s in zip(_finite3(name, values), scales, strict=True)]
    if not all(-0x8000 <= r <= 0x7FFF for r in raws):
        raise ValueRangeError(f'HiPNUC legacy {name} {values!r} does not fit int16')
    return _I16X3.pack(*raws)


def encode_legacy(
    *,
    acc: Vector3 | None = None,
    gyr: Vector3 | None = None,
    mag: Vector3 | None = None,
    euler: Vector3 | None = None,
    quat: tuple[float, float, float, float] | None = None,
    pressure: float | None = None,
    user_id: int | None = None,
) -> bytes:
    """Encode legacy items (0x90, 0xA0, 0xB0, 0xC0, 0xD0, 0xD1, 0xF0) into one payload.

    Args:
        acc: [m/s²] → 0xA0 (int16, g/1000).
        gyr: [rad/s] → 0xB0 (int16, 0.1 deg/s).
        mag: [µT] → 0xC0 (int16, 0.1).
        euler: (roll, pitch, yaw) [rad] → 0xD0 (pitch, roll 0.01°, yaw 0.1°).
        quat: (w, x, y, z) → 0xD1 (float32).
        pressure: [Pa] → 0xF0 (float32).
        user_id: 0..255 → 0x90.

    Raises:
        ValueRangeError: nothing to encode, or a value does not fit its field.
    """
    out = bytearray()
    if user_id is not None:
        if not 0 <= user_id <= 0xFF:
            raise ValueRangeError(f'HiPNUC user id {user_id} outside 0..255')
        out += bytes((TAG_USER_ID, user_id))
    if acc is not None:
        k = LEGACY_ACC_PER_G / STANDARD_GRAVITY
        out += bytes((TAG_ACC_RAW,)) + _i16x3('acc', acc, (k, k, k))
    if gyr is not None:
        k = LEGACY_GYR_PER_DEG_S / DEG_TO_RAD
        out += bytes((TAG_GYR_RAW,)) + _i16x3('gyr', gyr, (k, k, k))
    if mag is not None:
        k = LEGACY_MAG_PER_UT
        out += bytes((TAG_MAG_RAW,)) + _i16x3('mag', mag, (k, k, k))
    if euler is not None:
        roll, pitch, yaw = _finite3('euler', euler)
        pr = LEGACY_PITCH_ROLL_PER_DEG / DEG_TO_RAD
        out += bytes((TAG_EULER,)) + _i16x3(
            'euler', (pitch, roll, yaw), (pr, pr, LEGACY_YAW_PER_DEG / DEG_TO_RAD)
        )
    if quat is not None:
        out += bytes((TAG_QUAT,)) + _F32X4.pack(*_finite3('quat', quat, 4))
    if pressure is not None:
        if not math.isfinite(pressure):
            raise ValueRangeError(f'HiPNUC pressure {pressure!r} is not finite')
        out += bytes((TAG_PRESSURE,)) + _F32.pack(pressure)
    if not out:
        raise ValueRangeError('encode_legacy needs at least one item')
    return bytes(out)


class HipnucParser:
    """Streaming frame parser: feed it serial bytes, get :class:`ImuSample` objects.

    It resynchronises on the ``5A A5`` sync word after garbage, a bad length or a CRC
    failure (it then rescans from the byte after the false sync, so a real frame hidden
    inside a corrupted one is still found). Nothing raises; problems are counted.

    Attributes:
        frames_ok: frames decoded.
        crc_errors: frames whose CRC did not match.
        length_errors: headers with LEN 0 or above the maximum.
        decode_errors: frames with a good CRC but an undecodable payload.
        bytes_discarded: bytes dropped while looking for a frame.
    """

    def __init__(self, max_payload_length: int = MAX_PAYLOAD_LENGTH) -> None:
        self._buf = bytearray()
        self._max_payload = max_payload_length
        self.frames_ok = 0
        self.crc_errors = 0
        self.length_errors = 0
        self.decode_errors = 0
        self.bytes_discarded = 0
        self.last_error: str | None = None

    def feed(self, data: bytes | bytearray) -> list[ImuSample]:
        """Add received bytes; return the samples of every frame completed by them."""
        buf = self._buf
        buf += data
        out: list[ImuSample] = []
        while True:
            start = buf.find(SYNC)
            if start < 0:
                # Keep a trailing 0x5A: it may be the first half of the next sync word.
                keep = 1 if buf and buf[-1] == SYNC[0] else 0
                self._discard(len(buf) - keep)
                return out
            self._discard(start)
            if len(buf) < HEADER_LENGTH:
                return out
            length = buf[2] | (buf[3] << 8)
            if length == 0 or length > self._max_payload:
                self.length_errors += 1
                self.last_error = f'bad LEN {length}'
                self._discard(1)
                continue
            end = HEADER_LENGTH + length
            if len(buf) < end:
                return out
            frame = bytes(buf[:end])
            crc = buf[4] | (buf[5] << 8)
            if frame_crc(frame) != crc:
                self.crc_errors += 1
                self.last_error = f'CRC mismatch in a {end}-byte frame'
                self._discard(1)
                continue
            del buf[:end]
            try:
                out.append(decode_payload(frame[HEADER_LENGTH:]))
            except ProtocolError as err:
                self.decode_errors += 1
                self.last_error = str(err)
                continue
            self.frames_ok += 1

    def _discard(self, n: int) -> None:
        if n > 0:
            del self._buf[:n]
            self.bytes_discarded += n
