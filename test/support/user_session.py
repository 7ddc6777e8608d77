"""A user at two terminals: `make run` in one, README's commands typed into the other.

    with UserSession(tmp_path, robot='hero') as user:
        user.type(readme_blocks('Drive the simulated robot')[0])
        line = user.status.wait_for(lambda s: 'chassis GYRO' in s)

The robot is `make -s run` (or another of README's commands, such as a bringup: the robot
with its status line, one line every 2 s without a terminal), its log in ``run.log``; each
typed script runs in bash from the repository root after README's ``source
scripts/env.sh``, its output in ``user-N.log``. Both get the test's private ROS domain,
localhost-only discovery and a ROS_HOME of their own. On exit every script is stopped
(SIGTERM to its process group), then the robot with Ctrl-C (SIGINT), as a user does.
"""

from __future__ import annotations

import os
import pathlib
import re
import signal
import subprocess
import time
from collections.abc import Callable
from typing import Any

import yaml

from support.ros import isolate_ros_environment

ROOT = pathlib.Path(__file__).resolve().parents[2]
WAIT = 60.0  # [s] longest wait for any status README promises


def readme_blocks(section: str) -> list[str]:
    """The bash blocks of one README section, in order."""
    text = (ROOT / 'README.md').read_text(encoding='utf-8')
    start = text.index(f'## {section}\n')
    end = text.find('\n## ', start + 1)
    return re.findall(r'```bash\n(.*?)```', text[start:end], flags=re.S)


def readme_yaml(section: str) -> Any:
    """The one YAML block of a README section, loaded."""
    text = (ROOT / 'README.md').read_text(encoding='utf-8')
    start = text.index(f'## {section}\n')
    end = text.find('\n## ', start + 1)
    (block,) = re.findall(r'```yaml\n(.*?)```', text[start:end], flags=re.S)
    return yaml.safe_load(block)


def user_environment(**extra: str) -> dict[str, str]:
    """os.environ on the test's private domain, localhost only, plus extra."""
    env = dict(os.environ)
    isolate_ros_environment(env)
    env.update(extra)
    return env


def shots(line: str) -> int:
    """The shots of a status line's shooter part (-1 without one)."""
    found = re.search(r'shooter \w+ (\d+) shots', line)
    return int(found.group(1)) if found else -1


class StatusLines:
    """`make run`'s status lines as they come."""

    def __init__(self, process: subprocess.Popen) -> None:
        self.process, self.lines = process, []

    def wait_for(self, predicate: Callable[[str], object], timeout: float = WAIT) -> str | None:
        """The first new line that satisfies predicate, or None after timeout [s]."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.process.poll() is None:
            line = self.process.stdout.readline()
            if line:
                self.lines.append(line.rstrip())
                if predicate(line):
                    return line
        return None

    def read_for(self, seconds: float) -> list[str]:
        """Every line that comes within seconds."""
        start = len(self.lines)
        self.wait_for(lambda _line: False, seconds)
        return self.lines[start:]


class UserSession:
    """`make run` and a second terminal (see the module docstring)."""

    def __init__(self, tmp: pathlib.Path, *, robot: str = 'standard',
                 command: list[str] | None = None) -> None:
        self.tmp = tmp
        # a user's own ~/.ros (calibration kept between two runs of one test, not beyond)
        self.env = user_environment(ROBOT=robot, ROS_HOME=str(tmp / 'ros_home'))
        self._scripts: list[subprocess.Popen] = []
        self.robot = subprocess.Popen(
            command or ['make', '-s', 'run'], cwd=ROOT, env=self.env, text=True,
            stdout=subprocess.PIPE, stderr=open(tmp / 'run.log', 'w'), start_new_session=True,
        )
        self.status = StatusLines(self.robot)

    def __enter__(self) -> UserSession:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def log(self) -> str:
        """The robot's log so far."""
        return (self.tmp / 'run.log').read_text()

    def wait_for_robot(self, *, on_clock: bool = False) -> None:
        """Until the first status line with the chassis in it.

        on_clock: a robot on /clock (--sim-time) reports nothing before the clock runs;
        then until its first status line, whatever it says.
        """
        first = (lambda s: True) if on_clock else (lambda s: s.startswith('chassis '))
        assert self.status.wait_for(first), self.log[-2000:]

    def workdir(self) -> pathlib.Path:
        """A folder of the user's own to type in: what README's commands write lands there.

        It holds the repository's ``scripts`` and ``test`` (links), which README's commands
        name by relative paths (``source scripts/env.sh``, ``test/data/teleop``).
        """
        home = self.tmp / 'work'
        if not home.exists():
            home.mkdir()
            for name in ('scripts', 'test'):
                (home / name).symlink_to(ROOT / name)
        return home

    def output(self, n: int) -> str:
        """What the n-th typed script printed so far."""
        return (self.tmp / f'user-{n}.log').read_text()

    def type(self, commands: str, *, wait: bool = False, timeout: float = WAIT,
             cwd: pathlib.Path = ROOT) -> str:
        """Run commands in the second terminal; with wait, until they end: their output."""
        n = len(self._scripts)
        script, out = self.tmp / f'user-{n}.sh', self.tmp / f'user-{n}.log'
        script.write_text(f'source scripts/env.sh\n{commands}\n' + ('' if wait else 'wait\n'))
        process = subprocess.Popen(['bash', str(script)], cwd=cwd, env=self.env,
                                   stdout=open(out, 'w'), stderr=subprocess.STDOUT,
                                   start_new_session=True)
        self._scripts.append(process)
        return self.wait_typed(n, timeout) if wait else ''

    def wait_typed(self, n: int, timeout: float = WAIT) -> str:
        """Until the n-th typed script ends (with success): its output."""
        process, out = self._scripts[n], self.tmp / f'user-{n}.log'
        try:
            process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            _signal_group(process, signal.SIGTERM)
            _stop(process)
            # what the user saw, and the robot's side, for the flake seen once
            raise AssertionError(
                f'{(self.tmp / f"user-{n}.sh").read_text()!r} did not end in {timeout:g} s; '
                f'it printed:\n{out.read_text()}\n--- the robot, last lines:\n'
                f'{self.log[-3000:]}\n--- its status lines, last:\n'
                + '\n'.join(self.status.lines[-5:])
            ) from None
        text = out.read_text()
        assert process.returncode == 0, text
        return text

    def close(self) -> None:
        """Stop the typed scripts and all they started, then the robot with Ctrl-C."""
        for process in self._scripts:
            _signal_group(process, signal.SIGTERM)
        for process in self._scripts:
            _stop(process)
        if self.robot.poll() is None:
            os.killpg(self.robot.pid, signal.SIGINT)
        try:
            self.robot.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(self.robot.pid, signal.SIGKILL)
            self.robot.wait()


def _signal_group(process: subprocess.Popen, signum: int) -> bool:
    """Send signum to the process group of a typed script; False if the group is gone."""
    try:
        os.killpg(process.pid, signum)
    except ProcessLookupError:
        return False
    return True


def _stop(process: subprocess.Popen, timeout_s: float = 30.0) -> None:
    """Wait until a typed script's process group is gone: its commands too, not the script only.

    A command it put in the background outlives the script, and an orphan left running
    slows every test after it (an `rmcli topic pub` once spun a core for 11 minutes).
    After close()'s SIGTERM, SIGKILL to whatever of the group is left after timeout_s.
    """
    deadline = time.monotonic() + timeout_s
    killed = False
    while True:
        process.poll()  # reaps the script: a zombie still counts as the group's
        if not _signal_group(process, 0):
            break
        if not killed and time.monotonic() > deadline:
            _signal_group(process, signal.SIGKILL)
            killed = True  # then until init has reaped the orphans: they count until then
            deadline = time.monotonic() + 10.0
        elif killed and time.monotonic() > deadline:
            break
        time.sleep(0.1)
    process.wait()
