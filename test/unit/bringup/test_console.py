"""bringup's console: log lines scroll above the status line, none cut into it."""

import os
import pty

from rm_bringup.console import Console


def read_all(fd: int) -> bytes:
    out = b''
    while True:
        try:
            chunk = os.read(fd, 65536)
        except OSError:  # the pty's other end closed
            return out
        if not chunk:
            return out
        out += chunk


def test_a_log_line_goes_above_the_status_line_which_is_drawn_again():
    # The finding: log lines broke into the status line of `make run`.
    master, terminal = pty.openpty()
    log = os.open(os.devnull, os.O_WRONLY)  # stands for stderr
    console = Console(terminal_fd=terminal, log_fd=log)
    console.show('chassis GYRO | hp 200/200')
    os.write(log, b'[WARN] one line\n[INFO] half a ')
    os.write(log, b'line\n[INFO] no newline at the end')
    console.close()
    os.close(log)
    os.close(terminal)
    seen = read_all(master).replace(b'\r\n', b'\n')
    os.close(master)
    erase = b'\r\x1b[K'
    parts = seen.split(erase)
    # each log line starts on an erased line and is followed by the status line again
    assert b'[WARN] one line\n' in seen and b'[INFO] half a line\n' in seen
    assert b'[INFO] no newline at the end\n' in seen
    logs = [p for p in parts if p.startswith(b'[')]
    assert all(p.endswith(b'chassis GYRO | hp 200/200') for p in logs), parts
    assert seen.endswith(erase + b'chassis GYRO | hp 200/200\n')  # left on its own line


def test_closing_gives_stderr_back():
    master, terminal = pty.openpty()
    read_end, write_end = os.pipe()
    console = Console(terminal_fd=terminal, log_fd=write_end)
    console.close()
    os.write(write_end, b'after')
    assert os.read(read_end, 16) == b'after'
    for fd in (read_end, write_end, terminal, master):
        os.close(fd)
