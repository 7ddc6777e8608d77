"""A command in a pseudo-terminal, typed at as a user does: `rmcli teleop` reads keys."""

from __future__ import annotations

import os
import pty
import subprocess
import threading
import time

from support.user_session import ROOT

REPEAT_DELAY_S, REPEAT_S = 0.5, 0.033  # a keyboard's autorepeat


class Terminal:
    """A command in a pseudo-terminal: keys in, screen out (kept whole)."""

    def __init__(self, command: str, env: dict[str, str]) -> None:
        self._master, slave = pty.openpty()
        # a session of its own whose terminal this is: Ctrl-C typed there is SIGINT
        self.process = subprocess.Popen(
            ['setsid', '--ctty', 'bash', '-c', command], cwd=ROOT, env=env,
            stdin=slave, stdout=slave, stderr=slave,
        )
        os.close(slave)
        self._screen = bytearray()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        while True:
            try:
                data = os.read(self._master, 4096)
            except OSError:  # the command ended: EIO on the master
                return
            if not data:
                return
            self._screen += data

    @property
    def screen(self) -> str:
        return self._screen.decode(errors='replace')

    def hold(self, key: bytes, seconds: float) -> None:
        """Hold a key down for seconds, as a keyboard reports it."""
        end = time.monotonic() + seconds
        os.write(self._master, key)
        time.sleep(min(REPEAT_DELAY_S, seconds))
        while time.monotonic() < end:
            os.write(self._master, key)
            time.sleep(REPEAT_S)

    def tap(self, key: bytes) -> None:
        os.write(self._master, key)
        time.sleep(0.8)  # a tap holds the key 0.7 s: the next tap of it is a new press

    def wait_for(self, text: str, timeout: float = 30.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if text in self.screen:
                return True
            time.sleep(0.05)
        return False

    def close(self) -> int:
        if self.process.poll() is None:
            os.write(self._master, b'\x03')  # Ctrl-C, as typed
            try:
                self.process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, 9)
                self.process.wait()
        self._reader.join(timeout=5)
        os.close(self._master)
        return self.process.returncode
