"""README's "Record, plot and replay", typed as written after the drive examples.

One bash session types "Drive the simulated robot" and then "Record, plot and replay" line
by line (README's own lines; the test only adds `echo` markers between them, to know which
line runs). It must record ten seconds of GYRO, say what it holds, plot it with the modes
named, drive the robot again from the recording (`--restamp`) and from the teleop bag, and
reindex. Then the robot is started on /clock as README says and `bag play --clock` drives it
on the bag's time. Real time, generous bounds: a minute for any status README promises.
"""

import re

import pytest
from support.user_session import UserSession, readme_blocks

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

SECTION = 'Record, plot and replay'


def commanded(status: str) -> bool:
    """The chassis commanded by the external source (the replay), whoever has the rest."""
    return re.search(r'cmd (external|chassis:external)', status) is not None


def marked(block: str) -> str:
    """The block's lines, each announced by an echo of its number."""
    lines = [line for line in block.splitlines() if line.strip()]
    return '\n'.join(f'echo "== line {i}"\n{line}' for i, line in enumerate(lines)) + \
        '\necho "== done"'


def line_of(block: str, text: str) -> int:
    lines = [line for line in block.splitlines() if line.strip()]
    return next(i for i, line in enumerate(lines) if text in line)


def test_record_plot_and_both_ways_of_replay_do_what_readme_says(tmp_path):
    first, second = readme_blocks('Drive the simulated robot')[:2]
    record, robot_on_clock, play_clock = readme_blocks(SECTION)
    assert '--restamp' in record and '--sim-time' in robot_on_clock and '--clock' in play_clock
    with UserSession(tmp_path) as user:
        user.wait_for_robot()
        work = user.workdir()
        user.type(f'{first}\nsleep 12\n{second}\nsleep 5\n{marked(record)}', cwd=work)
        said = lambda: user.output(0)  # noqa: E731

        def after(text: str):
            mark = f'== line {line_of(record, text)}'
            return lambda s: mark in said()

        # the replay of run1: GYRO again, the live streams long stopped
        replayed = after('bag play run1 --restamp')
        line = user.status.wait_for(
            lambda s: replayed(s) and 'chassis GYRO' in s and commanded(s), 120.0)
        assert line, (said()[-2000:], user.status.lines[-3:])
        # the teleop bag: RAW, moving
        teleop = after('bag play test/data/teleop')
        line = user.status.wait_for(lambda s: teleop(s) and 'chassis RAW' in s, 60.0)
        assert line, (said()[-2000:], user.status.lines[-3:])
        assert user.status.wait_for(lambda s: '== done' in said(), 60.0) is not None or \
            '== done' in said(), said()[-2000:]
        out = said()
        recorded = re.search(r'Recording stopped: (\d+) messages', out)
        assert recorded and int(recorded.group(1)) > 500, out[-2000:]
        assert 'Topic: /chassis_cmd | Type: rm_msgs/msg/ChassisCmd' in out  # bag info
        assert '/chassis_cmd mode: GYRO' in out and 'GEAR_' not in out  # bag plot
        for png in ('chassis_velocity.png', 'gimbal.png', 'shooter.png'):
            assert (work / 'plots' / png).stat().st_size > 10_000, png
        assert 'not playing /chassis_state, /gimbal_state, /odom, /shooter_state' in out
        assert 'deprecated' not in out  # rcl's warning about --remap
        assert 'wrote run1/metadata.yaml' in out  # bag reindex
        assert 'rejected stale command' not in user.log
    # the other way: the robot on /clock, the bag's time
    clock = tmp_path / 'clock'
    clock.mkdir()
    with UserSession(clock, command=['bash', '-c', robot_on_clock]) as user:
        user.wait_for_robot(on_clock=True)
        user.type(play_clock, cwd=work)
        line = user.status.wait_for(lambda s: 'chassis GYRO' in s and commanded(s))
        assert line, (user.status.lines[-3:], user.log[-2000:])
        assert 'rejected stale command' not in user.log
