"""The terminal of `bringup`: log lines scroll above a status line kept at the bottom.

On a terminal the status line is rewritten in place (carriage return, erase, the line). A log line
written to stderr at the same time (by rcl, from any thread, or by rm_sim, a child) would
land in the middle of it. So the process's stderr is a pipe while the console runs: a
thread reads whole lines from it and writes each to the terminal as erase, the line, a
newline, then the status line again. Nothing is lost: a line without its newline yet waits
for the rest, and what is left when the console closes is written out.
"""

from __future__ import annotations

import os
import threading

_ERASE = b'\r\x1b[K'
_CHUNK = 65536


class Console:
    """Log lines above one status line on a terminal (see the module docstring).

    Args:
        terminal_fd: the terminal the status line and the log lines go to.
        log_fd: the descriptor log lines are written to (stderr); it becomes the pipe's
            writing end until :meth:`close`, and children started meanwhile inherit it.
    """

    def __init__(self, terminal_fd: int = 1, log_fd: int = 2) -> None:
        self._terminal = os.dup(terminal_fd)
        self._log_fd = log_fd
        self._saved = os.dup(log_fd)
        read_end, write_end = os.pipe()
        os.dup2(write_end, log_fd)
        os.close(write_end)
        self._lock = threading.Lock()
        self._status = b''
        self._reader = threading.Thread(
            target=self._pump, args=(read_end,), name='console', daemon=True
        )
        self._reader.start()

    def show(self, status: str) -> None:
        """Rewrite the status line."""
        with self._lock:
            self._status = status.encode(errors='replace')
            os.write(self._terminal, _ERASE + self._status)

    def close(self) -> None:
        """Give stderr back, write out what the pipe still holds, end the status line."""
        os.dup2(self._saved, self._log_fd)  # our end of the pipe closes: the reader sees EOF
        os.close(self._saved)
        self._reader.join(timeout=2.0)  # a child still holding the pipe would keep it open
        with self._lock:
            os.write(self._terminal, _ERASE + self._status + b'\n')
            self._status = b''
        os.close(self._terminal)

    def _pump(self, read_end: int) -> None:
        pending = b''
        try:
            while chunk := os.read(read_end, _CHUNK):
                pending += chunk
                lines, _, pending = pending.rpartition(b'\n')
                if lines:
                    self._above(lines + b'\n')
        finally:
            if pending:
                self._above(pending + b'\n')
            os.close(read_end)

    def _above(self, lines: bytes) -> None:
        with self._lock:
            os.write(self._terminal, _ERASE + lines + self._status)
