"""DJI DR16 receiver (DT7 remote) DBUS frames: 18 bytes, UART 100000 bps 8E1.

docs/PROTOCOLS.md §5 (DJI Dev-Board-C ``remote_control.c``, rm_control ``rm_dbus``)::

    bits 0..43   four 11-bit stick channels, raw 364..1684, centre 1024
    bits 44..45  switch A        bits 46..47  switch B      (1 UP, 3 MID, 2 DOWN)
    bytes 6..11  mouse x, y, z   int16 LE
    bytes 12, 13 mouse left, right (1 = pressed)
    bytes 14..15 keyboard bitmap uint16 LE (bit 0 W ... bit 15 B)
    bytes 16..17 wheel (dial), uint16 LE, raw 364..1684, centre 1024

Channels and the wheel are reported centred and clamped to −660..660. Like DJI's decoder,
a frame with a channel up to ±700 is accepted (a worn stick overshoots 660) and clamped; one
beyond ±700, or with a switch value other than 1/2/3, is rejected (a glitch on the UART must
never become a stick command).

The frame has no header or checksum: the receiver sends its 18 bytes in one burst every
14 ms, and a frame is the bytes between two silences (:class:`DbusStream`, as DJI's DMA
idle-line interrupt does). The mouse buttons are 0 or 1: any other byte there is noise.

Without a checksum about one random 18-byte burst in 400 passes the range checks, so a
decoded frame is not yet the operator: :class:`DbusTrust` believes the remote only once it
behaves like a DR16 (docs/PROTOCOLS.md §5.1).

UNVERIFIED: which physical switch is on bits 44–45. rm_control and RoboRTS say the
right one, DJI's example comment says the left; the fields are therefore named
``switch_a`` (bits 44–45) and ``switch_b`` (bits 46–47) — map them in the config.
"""

from __future__ import annotations

import dataclasses
import enum
import struct
import time
from collections.abc import Callable

from rm_base.hardware.errors import FrameLengthError, ValueRangeError

FRAME_LENGTH = 18
CHANNEL_OFFSET = 1024
CHANNEL_RANGE = 660
#: Channels up to this far from centre are accepted and clamped to CHANNEL_RANGE (DJI).
CHANNEL_ACCEPT = 700
CHANNEL_MASK = 0x7FF
BAUD_RATE = 100_000
#: The receiver's frame period [s].
FRAME_PERIOD_S = 0.014
#: Silence that ends a frame [s]: the 18 bytes take 2 ms at 100 kbaud, frames are 14 ms apart.
FRAME_GAP_S = 0.004

_TAIL = struct.Struct('<3hBBHH')  # bytes 6..17


class Switch(enum.IntEnum):
    """Three-position switch values."""

    UP = 1
    DOWN = 2
    MID = 3


class Key(enum.IntFlag):
    """Keyboard bitmap bits."""

    W = 1 << 0
    S = 1 << 1
    A = 1 << 2
    D = 1 << 3
    SHIFT = 1 << 4
    CTRL = 1 << 5
    Q = 1 << 6
    E = 1 << 7
    R = 1 << 8
    F = 1 << 9
    G = 1 << 10
    Z = 1 << 11
    X = 1 << 12
    C = 1 << 13
    V = 1 << 14
    B = 1 << 15


@dataclasses.dataclass(frozen=True)
class DbusFrame:
    """One decoded DBUS frame.

    Attributes:
        channels: (ch0, ch1, ch2, ch3), each −660..660 (rm_control: right X, right Y,
            left X, left Y).
        switch_a: bits 44–45 (right switch per rm_control; UNVERIFIED).
        switch_b: bits 46–47.
        mouse: (x, y, z) int16 speeds.
        mouse_left: left button pressed.
        mouse_right: right button pressed.
        keys: keyboard bitmap (see :class:`Key`).
        wheel: dial, −660..660.
    """

    channels: tuple[int, int, int, int] = (0, 0, 0, 0)
    switch_a: Switch = Switch.MID
    switch_b: Switch = Switch.MID
    mouse: tuple[int, int, int] = (0, 0, 0)
    mouse_left: bool = False
    mouse_right: bool = False
    keys: int = 0
    wheel: int = 0


def decode(data: bytes | bytearray) -> DbusFrame:
    """Decode one 18-byte frame.

    Raises:
        FrameLengthError: not 18 bytes.
        ValueRangeError: a channel or the wheel is beyond ±700, or a switch reads 0.
    """
    if len(data) != FRAME_LENGTH:
        raise FrameLengthError(f'DBUS frame must be 18 bytes, got {len(data)}')
    b0, b1, b2, b3, b4, b5 = data[:6]
    raw = (
        (b0 | (b1 << 8)) & CHANNEL_MASK,
        ((b1 >> 3) | (b2 << 5)) & CHANNEL_MASK,
        ((b2 >> 6) | (b3 << 2) | (b4 << 10)) & CHANNEL_MASK,
        ((b4 >> 1) | (b5 << 7)) & CHANNEL_MASK,
    )
    channels = (
        raw[0] - CHANNEL_OFFSET,
        raw[1] - CHANNEL_OFFSET,
        raw[2] - CHANNEL_OFFSET,
        raw[3] - CHANNEL_OFFSET,
    )
    mx, my, mz, left, right, keys, wheel_raw = _TAIL.unpack_from(data, 6)
    if left > 1 or right > 1:
        raise ValueRangeError(f'DBUS mouse buttons must be 0 or 1, got {left}, {right}')
    wheel = wheel_raw - CHANNEL_OFFSET
    for i, c in enumerate((*channels, wheel)):
        if not -CHANNEL_ACCEPT <= c <= CHANNEL_ACCEPT:
            name = f'channel {i}' if i < 4 else 'wheel'
            raise ValueRangeError(f'DBUS {name} {c} beyond ±{CHANNEL_ACCEPT}')
    c0, c1, c2, c3 = (_clamp(c) for c in channels)
    s_a = (b5 >> 4) & 0x3
    s_b = (b5 >> 6) & 0x3
    if s_a == 0 or s_b == 0:
        raise ValueRangeError(f'DBUS switch value 0 (switch_a {s_a}, switch_b {s_b})')
    return DbusFrame(
        (c0, c1, c2, c3), Switch(s_a), Switch(s_b), (mx, my, mz), bool(left), bool(right), keys,
        _clamp(wheel),
    )


def _clamp(value: int) -> int:
    return max(-CHANNEL_RANGE, min(CHANNEL_RANGE, value))


def encode(frame: DbusFrame) -> bytes:
    """Encode one frame (receiver side, for the simulator and tests).

    Raises:
        ValueRangeError: a field outside its range.
    """
    if len(frame.channels) != 4:
        raise ValueRangeError(f'DBUS needs 4 channels, got {len(frame.channels)}')
    for c in (*frame.channels, frame.wheel):
        if not -CHANNEL_RANGE <= c <= CHANNEL_RANGE:
            raise ValueRangeError(f'DBUS channel/wheel {c} outside ±{CHANNEL_RANGE}')
    try:
        s_a, s_b = Switch(frame.switch_a), Switch(frame.switch_b)
    except ValueError as err:
        raise ValueRangeError(f'DBUS switch must be 1, 2 or 3: {err}') from err
    if not 0 <= frame.keys <= 0xFFFF:
        raise ValueRangeError(f'DBUS key bitmap {frame.keys} outside uint16')
    c0, c1, c2, c3 = (c + CHANNEL_OFFSET for c in frame.channels)
    bits = c0 | (c1 << 11) | (c2 << 22) | (c3 << 33) | (s_a << 44) | (s_b << 46)
    try:
        tail = _TAIL.pack(
            *frame.mouse,
            int(frame.mouse_left),
            int(frame.mouse_right),
            frame.keys,
            frame.wheel + CHANNEL_OFFSET,
        )
    except struct.error as err:
        raise ValueRangeError(f'DBUS mouse {frame.mouse!r} does not fit int16: {err}') from err
    return bits.to_bytes(6, 'little') + tail


#: Frames a remote must send in a row, each in rhythm and consistent, before it is believed.
TRUST_FRAMES = 3
#: A channel that moves more than this between two frames 14 ms apart has jumped [counts].
JUMP_COUNTS = 400


def jumped(a: DbusFrame, b: DbusFrame) -> bool:
    """Whether b jumps every stick and the wheel at once from a (no hand does: noise)."""
    before, after = (*a.channels, a.wheel), (*b.channels, b.wheel)
    return all(abs(x - y) > JUMP_COUNTS for x, y in zip(before, after, strict=True))


class DbusTrust:
    """Believes a DR16 only when its frames come as a DR16 sends them.

    A frame is in rhythm when it comes at least half a frame period after the one before
    (a receiver sends one every 14 ms; bursts closer than that are noise) and within
    ``timeout_s`` of it; it is consistent when it does not jump every channel at once
    (:func:`jumped`). The remote is believed after :data:`TRUST_FRAMES` such frames in a
    row, and stays believed while they keep coming within ``timeout_s``; a frame out of
    rhythm or jumping is dropped and counted (``noise_frames``), and while the remote is
    not yet believed it starts the count again.

    Args:
        timeout_s: longest gap between two frames of one stream [s] (the link's data
            timeout): after a longer one the remote must earn trust again.
    """

    def __init__(self, timeout_s: float) -> None:
        self._timeout_ns = round(timeout_s * 1e9)
        self._min_gap_ns = round(FRAME_PERIOD_S / 2 * 1e9)
        self._last: DbusFrame | None = None
        self._last_ns: int | None = None
        self._streak = 0
        self.noise_frames = 0

    @property
    def believed(self) -> bool:
        """Whether the last frames earned trust (until a gap longer than the timeout)."""
        return self._streak >= TRUST_FRAMES

    def accept(self, frame: DbusFrame, now_ns: int) -> bool:
        """Take a decoded frame received at now_ns; return whether it is the operator's."""
        last, last_ns = self._last, self._last_ns
        if last is None or last_ns is None or now_ns - last_ns > self._timeout_ns:
            self._last, self._last_ns, self._streak = frame, now_ns, 1
            return False
        if now_ns - last_ns < self._min_gap_ns or jumped(last, frame):
            self.noise_frames += 1
            if not self.believed:
                self._last, self._last_ns, self._streak = frame, now_ns, 1
            return False
        self._last, self._last_ns = frame, now_ns
        self._streak = min(self._streak + 1, TRUST_FRAMES)
        return self.believed


class DbusStream:
    """Splits a DBUS byte stream into frames at the silences between them.

    Bytes that arrive within ``FRAME_GAP_S`` of the previous ones belong to the same frame;
    after a silence a new frame begins and an incomplete one is dropped. Complete frames
    are decoded; an invalid one is counted and dropped. The reader's counters
    (``rm_plugins.serial.reader.FrameStream``): there is no CRC, so ``crc_errors`` stays 0.

    Args:
        clock: monotonic time [ns] of the bytes being fed (``time.monotonic_ns``).
    """

    crc_errors = 0

    def __init__(self, clock: Callable[[], int] = time.monotonic_ns) -> None:
        self._clock = clock
        self._gap_ns = round(FRAME_GAP_S * 1e9)
        self._buffer = bytearray()
        self._last_ns: int | None = None
        self.frames_ok = 0
        self.length_errors = 0
        self.decode_errors = 0
        self.bytes_discarded = 0

    def feed(self, data: bytes) -> list[DbusFrame]:
        """Add the bytes of one read; return the frames they completed."""
        now = self._clock()
        if self._last_ns is not None and now - self._last_ns > self._gap_ns and self._buffer:
            self.length_errors += 1  # a frame cut short (or bytes from mid-frame at start)
            self.bytes_discarded += len(self._buffer)
            self._buffer.clear()
        self._last_ns = now
        self._buffer += data
        frames = []
        while len(self._buffer) >= FRAME_LENGTH:
            chunk = bytes(self._buffer[:FRAME_LENGTH])
            del self._buffer[:FRAME_LENGTH]
            try:
                frames.append(decode(chunk))
            except ValueRangeError:
                self.decode_errors += 1
                self.bytes_discarded += FRAME_LENGTH
                continue
            self.frames_ok += 1
        return frames
