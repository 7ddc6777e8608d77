"""README from "Drive the simulated robot" to "Record, plot and replay", typed as written.

`make run`, then one bash session types the drive examples and then "Record, plot and
replay" line by line (README's own lines; the test only adds `echo` markers between the
replay block's lines, to know which runs). The status lines of `make run` (one every 2 s
without a terminal) must say what README says: GYRO spinning with the gimbal on RATE and
the shooter READY, then the move and the burst of five, no more. Then it must record ten
seconds of GYRO, say what it holds, plot it with the modes
named, drive the robot again from the recording (`--restamp`) and from the teleop bag, and
reindex. Then the robot is started on /clock as README says and `bag play --clock` drives it
on the bag's time. Real time, generous bounds: a minute for any status README promises.
"""

import re

import pytest
from support.user_session import UserSession, readme_blocks, shots

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

SECTION = 'Record, plot and replay'


def commanded(status: str) -> bool:
    """The chassis commanded by the external source (the replay), whoever has the rest."""
    return re.search(r'cmd (external|chassis:external)', status) is not None


def replayed_stale(log: str) -> list[str]:
    """Commands refused as older than a second: recorded stamps (the finding: 168 s old).

    A live stream that stalls a few hundred ms on a loaded machine is refused too, and
    is not what this test is about.
    """
    return [m.group(0) for m in re.finditer(r'rejected stale command on (\S+): stamp is '
                                            r'([\d.]+) s old', log) if float(m.group(2)) > 1.0]


def marked(block: str) -> str:
    """The block's lines, each announced by an echo of its number."""
    lines = [line for line in block.splitlines() if line.strip()]
    return '\n'.join(f'echo "== line {i}"\n{line}' for i, line in enumerate(lines)) + \
        '\necho "== done"'


def line_of(block: str, text: str) -> int:
    lines = [line for line in block.splitlines() if line.strip()]
    return next(i for i, line in enumerate(lines) if text in line)


def check_the_drive_examples(user: UserSession) -> None:
    """"Drive the simulated robot": GYRO, RATE, READY; then POSITION and a burst of five."""
    status = user.status
    line = status.wait_for(lambda s: 'chassis GYRO' in s and 'gimbal RATE' in s
                           and 'shooter READY' in s and 'cmd external' in s)
    assert line, status.lines[-3:]
    spin = float(re.search(r'chassis GYRO v\([-\d.]+,[-\d.]+,([-\d.]+)\)', line).group(1))
    assert spin > 2.0, line  # spinning
    line = status.wait_for(lambda s: 'chassis POSITION' in s and shots(s) >= 5, 30.0)
    if line is None:
        # A stall of the publisher over the shooter's 0.2 s command timeout ends a burst
        # (the same burst_id does not fire again): then the log must say so.
        assert 'PUSH -> PASSIVE: no command on /shoot_cmd' in user.log, status.lines[-3:]
        assert any('chassis POSITION' in s for s in status.lines), status.lines[-3:]
        assert 1 <= max(map(shots, status.lines)) <= 5, status.lines[-3:]
        return
    assert shots(line) == 5, line
    later = status.wait_for(lambda s: s.startswith('chassis '))
    assert later and shots(later) == 5, later  # five, not more


def check_a_refused_command(user: UserSession) -> None:
    """README: the status line says `refused chassis` after a refused command, the log
    why, once (a bad message while there is no valid command: one warning, not two)."""
    said = user.type("rmcli topic pub --once /chassis_cmd rm_msgs/msg/ChassisCmd "
                     "'{header: auto, mode: 250}'", wait=True)
    assert 'publishing #1' in said, said
    line = user.status.wait_for(lambda s: 'refused chassis' in s)
    assert line and 'chassis PASSIVE' in line, user.status.lines[-3:]
    warnings = [text for text in user.log.splitlines()
                if '[WARN]' in text and 'unknown mode 250' in text]
    assert len(warnings) == 1, warnings
    assert warnings[0].endswith('rejected /chassis_cmd: unknown mode 250 (known: 0=PASSIVE, '
                                '1=RAW, 2=FOLLOW, 3=TWIST, 4=GYRO, 5=POSITION); no valid '
                                'command has come yet'), warnings


def test_readme_from_driving_to_replay_does_what_it_says(tmp_path):
    first, second = readme_blocks('Drive the simulated robot')[:2]
    assert 'mode: GYRO' in first and 'mode: POSITION' in second  # the README we test
    record, robot_on_clock, play_clock = readme_blocks(SECTION)
    assert '--restamp' in record and '--sim-time' in robot_on_clock and '--clock' in play_clock
    with UserSession(tmp_path) as user:
        user.wait_for_robot()
        check_a_refused_command(user)
        work = user.workdir()
        user.type(f'{first}\nsleep 12\n{second}\nsleep 8\n{marked(record)}', cwd=work)
        check_the_drive_examples(user)
        said = lambda: user.output(1)  # noqa: E731  (script 0: the refused command)

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
        assert not replayed_stale(user.log), replayed_stale(user.log)
    # the other way: the robot on /clock, the bag's time
    clock = tmp_path / 'clock'
    clock.mkdir()
    with UserSession(clock, command=['bash', '-c', robot_on_clock]) as user:
        user.wait_for_robot(on_clock=True)
        user.type(play_clock, cwd=work)
        line = user.status.wait_for(lambda s: 'chassis GYRO' in s and commanded(s))
        assert line, (user.status.lines[-3:], user.log[-2000:])
        assert not replayed_stale(user.log), replayed_stale(user.log)
