"""A simulated serial port: a pseudo-terminal whose device is symlinked at a configured path.

The simulated devices on a UART (the Hi220 IMU, the referee system, the DR16 receiver)
write their frames into the master side of a pseudo-terminal (``os.openpty``); its slave
device is symlinked at the configured path, so the driver opens that path with pyserial
exactly as it opens ``/dev/ttyUSB0`` on a robot.

Like a real UART nobody reads, the terminal's buffer can fill up; then its stale input is
flushed and the frame is dropped (counted). pyserial flushes the input when it opens the
port, so a reader never starts with old frames.
"""

from __future__ import annotations

import contextlib
import errno
import os
import termios
import threading
import tty

from rm_base.sim_devices.errors import SimConfigError


def expand_path(path: str) -> str:
    """Expand ``~`` and environment variables (``${ROS_DOMAIN_ID}``) in a path.

    Raises:
        SimConfigError: a variable is not set (the ``$`` would stay in the path).
    """
    expanded = os.path.expanduser(os.path.expandvars(path))
    if '$' in expanded:
        raise SimConfigError(f'path {path!r} uses an unset environment variable')
    return expanded


class PtyPort:
    """One end of a simulated serial link (see the module docstring).

    Attributes:
        path: the configured path (symlink to the terminal), expanded.
        device_path: the pseudo-terminal's slave device (``/dev/pts/N``).
        frames_written: frames written whole.
        frames_dropped: frames dropped because nobody read the terminal (or it was closed).
    """

    def __init__(self, path: str, owner: str) -> None:
        """Open the terminal and create the symlink.

        Args:
            path: where to put the symlink; ``~`` and ``${VAR}`` are expanded, missing
                directories are created, a stale symlink is replaced.
            owner: the device's name, for error messages.

        Raises:
            SimConfigError: the path exists and is not a symlink, or cannot be created.
        """
        self.path = expand_path(path)
        self.frames_written = 0
        self.frames_dropped = 0
        self._closed = False
        self._io_lock = threading.Lock()  # write vs close (the fds must not be reused)
        if os.path.lexists(self.path) and not os.path.islink(self.path):
            raise SimConfigError(f'{owner}: {self.path} exists and is not a symlink')
        self._master, self._slave = os.openpty()
        try:
            # Raw mode: no echo, no CR/LF translation, no XON/XOFF on 0x11/0x13 bytes.
            tty.setraw(self._slave)
            os.set_blocking(self._master, False)
            self.device_path = os.ttyname(self._slave)
            directory = os.path.dirname(self.path)
            if directory:
                os.makedirs(directory, exist_ok=True)
            if os.path.islink(self.path):
                os.unlink(self.path)
            os.symlink(self.device_path, self.path)
        except OSError as err:
            self._close_fds()
            raise SimConfigError(
                f'{owner}: cannot create the terminal at {self.path}: {err}'
            ) from err

    def write(self, data: bytes) -> None:
        """Write one frame; if the buffer is full, flush stale input and retry once.

        Safe against a concurrent :meth:`close` (the world writes outside its lock): a
        frame for a closed terminal is dropped.
        """
        with self._io_lock:
            if self._closed:
                self.frames_dropped += 1
                return
            self._write(data)

    def read(self) -> bytes:
        """What the other end wrote since the last call, without blocking; b'' if none."""
        with self._io_lock:
            if self._closed:
                return b''
            chunks = []
            while True:
                try:
                    chunk = os.read(self._master, 4096)
                except (BlockingIOError, OSError):  # nothing waits; EIO: nobody has it open
                    break
                if not chunk:
                    break
                chunks.append(chunk)
            return b''.join(chunks)

    def _write(self, data: bytes) -> None:
        for attempt in range(2):
            try:
                written = os.write(self._master, data)
            except BlockingIOError:
                written = 0
            except OSError as err:  # EIO: the terminal went away
                if err.errno != errno.EIO:
                    raise
                written = 0
            if written == len(data):
                self.frames_written += 1
                return
            if attempt == 0:
                with contextlib.suppress(termios.error):
                    termios.tcflush(self._slave, termios.TCIFLUSH)
                if written:
                    # A partial frame went out: the reader's parser resynchronises on it.
                    data = data[written:]
        self.frames_dropped += 1

    def close(self) -> None:
        """Close the terminal and remove the symlink (idempotent)."""
        with self._io_lock:
            if self._closed:
                return
            self._closed = True
            with contextlib.suppress(OSError):
                if os.path.islink(self.path) and os.readlink(self.path) == self.device_path:
                    os.unlink(self.path)
            self._close_fds()

    def _close_fds(self) -> None:
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._closed
