"""DescriptorReader: what a non-blocking file descriptor holds, read without releasing the GIL.

The control loop reads the serial ports itself (``SerialReader.poll``). ``os.read`` and
``select.poll`` release the interpreter lock around their system call, and on a 2-core
machine another Python thread (the CAN log writer, the outbox) then takes the interpreter
and the loop waits for it to hand it back: up to a switch interval, a late tick, a gap on
the wire (docs/PERFORMANCE.md, "Serial ports are read by the loop"). A ``poll(fd, 0)`` and a
non-blocking ``read`` take about a microsecond each, so this calls libc's through
``ctypes.PyDLL``, which keeps the lock. Linux only (the robot's platform).
"""

from __future__ import annotations

import ctypes
import errno
import os
import select

_libc = ctypes.PyDLL(None, use_errno=True)


class _PollFd(ctypes.Structure):
    _fields_ = (('fd', ctypes.c_int), ('events', ctypes.c_short), ('revents', ctypes.c_short))


_poll = _libc.poll
_poll.argtypes = (ctypes.POINTER(_PollFd), ctypes.c_ulong, ctypes.c_int)
_poll.restype = ctypes.c_int
_read = _libc.read
_read.argtypes = (ctypes.c_int, ctypes.c_void_p, ctypes.c_size_t)
_read.restype = ctypes.c_ssize_t


class DescriptorReader:
    """Reads up to ``size`` bytes of what fd holds, never blocking.

    Args:
        fd: an open descriptor (O_NONBLOCK, or a terminal with VMIN 0, as pyserial opens
            one); the caller keeps it open while it reads.
        size: most bytes one read returns.
    """

    def __init__(self, fd: int, size: int) -> None:
        self._pollfd = _PollFd(fd, select.POLLIN, 0)
        self._buffer = ctypes.create_string_buffer(size)
        self._size = size
        self.fd = fd

    def read(self) -> bytes:
        """What waits now; b'' if nothing.

        Raises:
            OSError: the read failed, or the device hung up (reports an event, has no data).
        """
        pollfd = self._pollfd
        ready = _poll(ctypes.byref(pollfd), 1, 0)
        if ready == 0:
            return b''
        if ready < 0:
            raise _os_error()
        n = _read(pollfd.fd, self._buffer, self._size)
        if n > 0:
            return self._buffer.raw[:n]
        if n < 0:
            if ctypes.get_errno() in (errno.EAGAIN, errno.EINTR):
                return b''
            raise _os_error()
        # An event (POLLIN, or POLLHUP on a terminal whose other side closed) and no byte.
        raise OSError(errno.EIO, 'the port reports data but has none (the device is gone)')


def _os_error() -> OSError:
    code = ctypes.get_errno()
    return OSError(code, os.strerror(code))
