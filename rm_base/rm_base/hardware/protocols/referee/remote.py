"""The 2025+ image-transmission module's remote frame (``A9 53``, 21 bytes, 921600 baud).

docs/PROTOCOLS.md §6.3. After the two header bytes, a little-endian bit stream::

    bits 0..43   ch0 right X, ch1 right Y, ch2 LEFT Y, ch3 left X: 11 bits each, 364..1684
                 (the left stick's axes are the other way round than on the DR16)
    bits 44..45  mode switch (0 C, 1 N, 2 S)
    bits 46..48  pause, custom-left, custom-right buttons
    bits 49..59  dial, 364..1684          bit 60  trigger
    bytes 10..15 mouse x, y, wheel (i16)  byte 16 mouse left (bits 0-1), right (2-3),
                 middle (4-5)             bytes 17..18 keyboard (DBUS bit order)
    bytes 19..20 CRC16 of bytes 0..18 (the referee CRC16)

Channels and the dial are given centred (-660..660); a frame with one outside that range
is rejected, as a glitch must never become a stick command.
"""

from __future__ import annotations

import enum
import struct
from dataclasses import dataclass

from rm_base.hardware.errors import FrameLengthError, ValueRangeError

PAYLOAD_LENGTH = 17
CHANNEL_OFFSET = 1024
CHANNEL_RANGE = 660
_MOUSE = struct.Struct('<hhhBH')  # bytes 10..18 of the frame


class ModeSwitch(enum.IntEnum):
    """The remote's three-position mode switch."""

    C = 0
    N = 1
    S = 2


@dataclass(frozen=True)
class RemoteFrame:
    """One decoded remote frame.

    Attributes:
        right_x, right_y, left_x, left_y: sticks, -660..660 (right / up larger).
        mode: the mode switch.
        pause, custom_left, custom_right, trigger: buttons pressed.
        dial: -660..660.
        mouse_x, mouse_y, mouse_wheel: mouse speeds as sent.
        mouse_left, mouse_right, mouse_middle: buttons pressed.
        keys: keyboard bitmap (:class:`rm_base.hardware.protocols.dbus.Key` order).
    """

    right_x: int
    right_y: int
    left_y: int
    left_x: int
    mode: ModeSwitch
    pause: bool
    custom_left: bool
    custom_right: bool
    dial: int
    trigger: bool
    mouse_x: int
    mouse_y: int
    mouse_wheel: int
    mouse_left: bool
    mouse_right: bool
    mouse_middle: bool
    keys: int


def _centred(raw: int, name: str) -> int:
    value = raw - CHANNEL_OFFSET
    if not -CHANNEL_RANGE <= value <= CHANNEL_RANGE:
        raise ValueRangeError(f'remote {name} {raw} outside 364..1684')
    return value


def decode_remote_payload(payload: bytes) -> RemoteFrame:
    """Decode the 17 bytes between the ``A9 53`` header and the CRC16.

    Raises:
        FrameLengthError: not 17 bytes.
        ValueRangeError: a channel or the dial out of range, or mode switch value 3.
    """
    if len(payload) != PAYLOAD_LENGTH:
        raise FrameLengthError(f'remote payload must be {PAYLOAD_LENGTH} bytes, got {len(payload)}')
    bits = int.from_bytes(payload[:8], 'little')
    sticks = [_centred((bits >> (11 * i)) & 0x7FF, f'channel {i}') for i in range(4)]
    mode = (bits >> 44) & 0x3
    if mode > ModeSwitch.S:
        raise ValueRangeError(f'remote mode switch value {mode}')
    x, y, wheel, buttons, keys = _MOUSE.unpack_from(payload, 8)
    return RemoteFrame(
        right_x=sticks[0],
        right_y=sticks[1],
        left_y=sticks[2],
        left_x=sticks[3],
        mode=ModeSwitch(mode),
        pause=bool(bits >> 46 & 1),
        custom_left=bool(bits >> 47 & 1),
        custom_right=bool(bits >> 48 & 1),
        dial=_centred((bits >> 49) & 0x7FF, 'dial'),
        trigger=bool(bits >> 60 & 1),
        mouse_x=x,
        mouse_y=y,
        mouse_wheel=wheel,
        mouse_left=bool(buttons & 0x03),
        mouse_right=bool(buttons & 0x0C),
        mouse_middle=bool(buttons & 0x30),
        keys=keys,
    )
