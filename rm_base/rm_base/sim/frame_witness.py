"""FrameWitness: knows when every socket on a kernel CAN interface has had a frame.

A lockstep run over the kernel (a stepped world joined to vcan by
:class:`~rm_base.sim.bus_peer.BusPeer`) must not start a tick before the frames of the
last one are in the robot's socket. On vcan a send usually delivers before it returns,
but the kernel may hand the delivery to ksoftirqd, so "usually" is not enough.

The witness is one more CAN_RAW socket on the interface whose filters are inverted ones
(``CAN_INV_FILTER``). The kernel delivers a frame to its receivers list by list, in a fixed
order: first the unfiltered sockets (python-can's, with no filters: the robot's and the
peer's), then masked filters, then inverted ones (``can_rcv_filter`` in net/can/af_can.c).
So once the witness has counted a frame, every unfiltered socket on that interface already
holds it. docs/KERNEL_CAN.md, "Lockstep over the kernel".
"""

from __future__ import annotations

import errno
import select
import socket
import struct
import time

#: linux/can.h
CAN_EFF_FLAG = 0x80000000
CAN_INV_FILTER = 0x20000000
#: Two inverted filters that together pass every data frame once: "not extended" and
#: "not standard" (each a frame the other one misses).
_FILTERS = struct.pack(
    '=IIII',
    CAN_INV_FILTER | CAN_EFF_FLAG, CAN_EFF_FLAG,
    CAN_INV_FILTER, CAN_EFF_FLAG,
)
#: struct can_frame / canfd_frame sizes; the witness counts, it does not decode.
_READ_BYTES = 72


class FrameWitness:
    """Counts the frames on one kernel CAN interface (see the module docstring).

    Args:
        interface: the kernel's interface name (``vcan0``).

    Raises:
        OSError: no such interface (errno 19) or no AF_CAN in this kernel.
    """

    def __init__(self, interface: str) -> None:
        self.interface = interface
        self.count = 0
        self.read_errors = 0
        self._sock = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
        try:
            self._sock.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_FILTER, _FILTERS)
            self._sock.setblocking(False)
            self._sock.bind((interface,))
        except OSError:
            self._sock.close()
            raise

    def drain(self) -> int:
        """Count every frame waiting now; return the total so far."""
        while True:
            try:
                self._sock.recv(_READ_BYTES)
            except BlockingIOError:
                return self.count
            except OSError as err:  # ENETDOWN once when the link goes down: nothing came
                if err.errno not in (errno.ENETDOWN, errno.ENXIO):
                    raise
                self.read_errors += 1
                return self.count
            self.count += 1

    def wait_for(self, total: int, timeout_s: float) -> bool:
        """Wait until total frames have been counted; False if timeout_s passed first."""
        deadline = time.monotonic() + timeout_s
        while self.drain() < total:
            left = deadline - time.monotonic()
            if left <= 0.0:
                return False
            select.select([self._sock], [], [], left)
        return True

    def close(self) -> None:
        """Close the socket."""
        self._sock.close()
