"""README's "Drive the simulated robot", typed as written: `make run`, then its command blocks.

The blocks are read out of README.md (not copied here) and run by bash in one session, as a
user types them into a second terminal, with README's `source scripts/env.sh` first; the
status lines of `make run` (one every 2 s without a terminal) must say what README says.
Real time, real executables; bounds are generous: the robot needs seconds, the test allows
a minute.
"""

import os
import pathlib
import re
import signal
import subprocess
import time

import pytest
from support.ros import isolate_ros_environment

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

ROOT = pathlib.Path(__file__).resolve().parents[2]
WAIT = 60.0  # [s] longest wait for any status README promises


def readme_blocks(section: str) -> list[str]:
    """The bash blocks of one README section, in order."""
    text = (ROOT / 'README.md').read_text(encoding='utf-8')
    start = text.index(f'## {section}\n')
    end = text.find('\n## ', start + 1)
    return re.findall(r'```bash\n(.*?)```', text[start:end], flags=re.S)


class StatusLines:
    """`make run`'s status lines as they come."""

    def __init__(self, process: subprocess.Popen) -> None:
        self.process, self.lines = process, []

    def wait_for(self, predicate, timeout: float = WAIT) -> str | None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.process.poll() is None:
            line = self.process.stdout.readline()
            if line:
                self.lines.append(line.rstrip())
                if predicate(line):
                    return line
        return None


def shots(line: str) -> int:
    found = re.search(r'shooter \w+ (\d+) shots', line)
    return int(found.group(1)) if found else -1


def test_the_drive_examples_do_what_readme_says(tmp_path):
    env = dict(os.environ)
    isolate_ros_environment(env)
    blocks = readme_blocks('Drive the simulated robot')
    first, second = blocks[0], blocks[1]
    assert 'mode: GYRO' in first and 'mode: POSITION' in second  # the README we test
    robot = subprocess.Popen(['make', '-s', 'run'], cwd=ROOT, env=env, text=True,
                             stdout=subprocess.PIPE, stderr=open(tmp_path / 'run.log', 'w'),
                             start_new_session=True)
    status = StatusLines(robot)
    script = tmp_path / 'typed.sh'
    # the second terminal: the first block, a look at the robot, the second block, a look
    script.write_text(f'{first}\nsleep 12\n{second}\nsleep 600\n')
    user = None
    try:
        assert status.wait_for(lambda s: s.startswith('chassis ')), status.lines[-3:]
        user = subprocess.Popen(['bash', str(script)], cwd=ROOT, env=env,
                                stdout=open(tmp_path / 'user.log', 'w'),
                                stderr=subprocess.STDOUT, start_new_session=True)
        # "chassis GYRO ... gimbal RATE ... shooter READY", the commander in charge
        line = status.wait_for(lambda s: 'chassis GYRO' in s and 'gimbal RATE' in s
                               and 'shooter READY' in s and 'cmd external' in s)
        assert line, status.lines[-3:]
        spin = float(re.search(r'chassis GYRO v\([-\d.]+,[-\d.]+,([-\d.]+)\)', line).group(1))
        assert spin > 2.0, line  # spinning
        # then the move: POSITION, arrived and holding; and the burst of five
        line = status.wait_for(lambda s: 'chassis POSITION' in s and shots(s) >= 5, 30.0)
        if line is None:
            # A stall of the publisher over the shooter's 0.2 s command timeout ends a
            # burst (the same burst_id does not fire again): then the log must say so.
            log = (tmp_path / 'run.log').read_text()
            assert 'PUSH -> PASSIVE: no command on /shoot_cmd' in log, status.lines[-3:]
            assert any('chassis POSITION' in s for s in status.lines), status.lines[-3:]
            assert 1 <= max(map(shots, status.lines)) <= 5, status.lines[-3:]
            return
        assert shots(line) == 5, line
        time.sleep(3.0)
        later = status.wait_for(lambda s: s.startswith('chassis '))
        assert later and shots(later) == 5, later  # five, not more
    finally:
        for process in (user, robot):
            if process is not None and process.poll() is None:
                os.killpg(process.pid, signal.SIGINT if process is robot else signal.SIGTERM)
        if user is not None:
            user.wait(timeout=30)
        try:
            robot.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(robot.pid, signal.SIGKILL)
            robot.wait()
