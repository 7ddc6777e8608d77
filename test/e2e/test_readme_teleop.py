"""README's "Drive it by hand": `rmcli teleop --sim` in a terminal drives the simulated robot.

The command runs as typed, in a pseudo-terminal; the test is the operator at its keyboard:
a held key is its first byte, then the keyboard's repeats (after 0.5 s, every 33 ms). What
the robot does is read from `make run`'s status line: it drives forward, spins, fires,
and goes PASSIVE, all through rm_sim's DR16 receiver and the robot's rm_manual.
"""

from __future__ import annotations

import re
import time

import pytest
from support.terminal import Terminal
from support.user_session import UserSession, readme_blocks, shots

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

WAIT_S = 30.0  # [s] for the status line to show a change: it comes every 2 s; generous


def pose(line: str) -> tuple[float, float, float] | None:
    found = re.search(r'pose (-?[\d.]+) (-?[\d.]+) (-?\d+)deg', line)
    return tuple(map(float, found.groups())) if found else None


def spin_rate(line: str) -> float:
    found = re.search(r'chassis \w+ v\(-?[\d.]+,-?[\d.]+,(-?[\d.]+)\)', line)
    return float(found.group(1)) if found else 0.0


def test_teleop_drives_the_simulated_robot_forward_spins_it_and_fires(tmp_path):
    (block,) = readme_blocks('Drive it by hand')
    with UserSession(tmp_path) as user:
        user.wait_for_robot()
        status = user.status
        start = pose(status.lines[-1]) or (0.0, 0.0, 0.0)
        keyboard = Terminal(f'source scripts/env.sh && exec {block.strip()}', user.env)
        try:
            assert keyboard.wait_for('Ctrl-C quits'), keyboard.screen
            keyboard.hold(b'w', 2.0)
            line = status.wait_for(
                lambda s: (p := pose(s)) is not None and p[0] - start[0] > 0.8, WAIT_S)
            assert line and 'cmd manual' in line, (status.lines[-3:], keyboard.screen[-500:])
            assert 'right UP keys W mouse +0,+0 -> chassis FOLLOW NORMAL v +2.0 +0.0' \
                in keyboard.screen, keyboard.screen[-1000:]

            keyboard.tap(b'f')  # GYRO: the chassis spins
            line = status.wait_for(lambda s: 'chassis GYRO' in s and abs(spin_rate(s)) > 1.0,
                                   WAIT_S)
            assert line, (status.lines[-3:], keyboard.screen[-500:])
            keyboard.tap(b'f')
            assert status.wait_for(lambda s: 'chassis FOLLOW' in s, WAIT_S), status.lines[-3:]

            keyboard.tap(b'r')  # the friction wheels on, then fire while space is held
            assert status.wait_for(lambda s: 'shooter READY' in s, WAIT_S), status.lines[-3:]
            keyboard.hold(b' ', 2.0)
            line = status.wait_for(lambda s: shots(s) >= 3, WAIT_S)
            assert line, (status.lines[-3:], keyboard.screen[-500:])
            assert 'left -> chassis FOLLOW NORMAL v +0.0 +0.0 | gimbal RATE yaw +0.0 ' \
                'pitch +0.0 | shooter PUSH' in keyboard.screen, keyboard.screen[-1000:]

            keyboard.tap(b'p')  # the right switch down: everything PASSIVE
            line = status.wait_for(
                lambda s: 'chassis PASSIVE' in s and 'gimbal PASSIVE' in s, WAIT_S)
            assert line, (status.lines[-3:], keyboard.screen[-500:])
        finally:
            code = keyboard.close()
        assert code == 0, keyboard.screen[-1000:]
        assert keyboard.screen.rstrip().endswith('shooter PASSIVE'), keyboard.screen[-300:]
        # the receiver goes silent after the last frame: rm_manual loses the remote
        deadline = time.monotonic() + WAIT_S
        while 'remote lost' not in user.log and time.monotonic() < deadline:
            time.sleep(0.2)
        assert 'remote lost' in user.log, user.log[-2000:]
