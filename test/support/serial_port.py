"""Pseudo-terminals for serial-device tests: the test writes what a device would send."""

import contextlib
import os
import threading
import tty


class Pty:
    """A pseudo-terminal whose slave is symlinked at path."""

    def __init__(self, path):
        self.path = path
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        if os.path.lexists(path):  # a stale link from an earlier pty at this path
            os.unlink(path)
        os.symlink(os.ttyname(self.slave), path)

    def write(self, data):
        os.write(self.master, data)

    def close(self):
        with contextlib.suppress(OSError):
            os.unlink(self.path)
        for fd in (self.master, self.slave):
            with contextlib.suppress(OSError):
                os.close(fd)


class Streamer:
    """Writes a frame (from make_frame()) to a pty every period [s] in a thread."""

    def __init__(self, make_frame, period=0.005):
        self.make_frame = make_frame
        self.port = None
        self._period = period
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self, port):
        self.port = port
        self._thread.start()

    def _run(self):
        while not self._stop.wait(self._period):
            port = self.port
            if port is not None:
                with contextlib.suppress(OSError):
                    port.write(self.make_frame())

    def stop(self):
        """Stop writing (a streamer never started has nothing to stop)."""
        self._stop.set()
        if self._thread.ident is not None:
            self._thread.join()
