"""Datagrams between the robot and the rm_sim process: raw CAN frames, as SocketCAN has them.

One datagram carries the frames of one tick in one direction (the robot's frames of one
send, the motors' replies and feedback of one physics tick)::

    timestamp   float64, little-endian  [s since the epoch] when the frames were on the bus
    frames      n x 16 bytes, each a Linux ``struct can_frame``:
                can_id u32 (host order, flags in the top bits), len u8, 3 pad bytes, 8 data

``can_id`` flags are SocketCAN's: CAN_EFF_FLAG (extended id), CAN_RTR_FLAG (remote
frame), CAN_ERR_FLAG (error frame; rm_sim sends one with CAN_ERR_BUSOFF while a bus-off
fault is injected). A connection opens with a hello datagram naming the channel,
``HELLO + name``, answered by ``OK`` or ``ERR <reason>``. Pure: no sockets here.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable

import can

from rm_base.sim_devices.errors import SimError

HELLO = b'rm_sim 1 '
OK = b'OK'
ERR = b'ERR '

CAN_EFF_FLAG = 0x80000000
CAN_RTR_FLAG = 0x40000000
CAN_ERR_FLAG = 0x20000000
CAN_EFF_MASK = 0x1FFFFFFF
CAN_ERR_BUSOFF = 0x00000040  # error class: bus off

_STAMP = struct.Struct('<d')
_FRAME = struct.Struct('=IB3x8s')
FRAME_BYTES = _FRAME.size  # 16
MAX_DLC = 8


class WireError(SimError):
    """A datagram that is not frames of this format."""


def encode(frames: Iterable[can.Message], timestamp: float) -> bytes:
    """One datagram of frames (classic CAN only) at timestamp [s].

    Raises:
        WireError: a frame is CAN FD or carries more than 8 bytes.
    """
    parts = [_STAMP.pack(timestamp)]
    for msg in frames:
        if msg.is_fd or msg.dlc > MAX_DLC:
            raise WireError(f'frame 0x{msg.arbitration_id:X}: only classic CAN (<= 8 bytes)')
        can_id = msg.arbitration_id & CAN_EFF_MASK
        if msg.is_extended_id:
            can_id |= CAN_EFF_FLAG
        if msg.is_remote_frame:
            can_id |= CAN_RTR_FLAG
        if msg.is_error_frame:
            can_id |= CAN_ERR_FLAG
        parts.append(_FRAME.pack(can_id, msg.dlc, bytes(msg.data)))
    return b''.join(parts)


def decode(datagram: bytes, channel: str | None = None) -> list[can.Message]:
    """The frames of one datagram, stamped with its timestamp.

    Raises:
        WireError: the length is not a timestamp and whole frames, or a length byte is
            over 8.
    """
    body = len(datagram) - _STAMP.size
    if body < 0 or body % FRAME_BYTES:
        raise WireError(
            f'a datagram is 8 + n x {FRAME_BYTES} bytes; got {len(datagram)} bytes'
        )
    (timestamp,) = _STAMP.unpack_from(datagram)
    frames = []
    for can_id, dlc, data in _FRAME.iter_unpack(datagram[_STAMP.size:]):
        if dlc > MAX_DLC:
            raise WireError(f'frame 0x{can_id & CAN_EFF_MASK:X} has length {dlc} (> 8)')
        frames.append(
            can.Message(
                timestamp=timestamp,
                arbitration_id=can_id & CAN_EFF_MASK,
                is_extended_id=bool(can_id & CAN_EFF_FLAG),
                is_remote_frame=bool(can_id & CAN_RTR_FLAG),
                is_error_frame=bool(can_id & CAN_ERR_FLAG),
                dlc=dlc,
                data=data[:dlc],
                channel=channel,
                is_rx=True,
            )
        )
    return frames


def bus_off_frame() -> can.Message:
    """The error frame rm_sim sends while a bus-off fault is injected."""
    return can.Message(arbitration_id=CAN_ERR_BUSOFF, is_error_frame=True, dlc=0)
