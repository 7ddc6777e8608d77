"""README's drive examples on the hero (`ROBOT=hero make run`), held for 30 seconds.

The finding: about 10 s into READY/PUSH the hero's simulated referee destroyed the robot
(every motor offline for good) and nothing said why. Here README's two blocks run as typed,
and for 30 s (three times as long as the robot lasted) every status line must show the robot
whole: full HP, no output off, no motor offline, and the burst's five shots, no more.
"""

import pytest
from support.user_session import UserSession, readme_blocks, shots

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

SECONDS = 30.0


def test_the_hero_runs_readmes_shooter_examples_and_stays_whole(tmp_path):
    first, second = readme_blocks('Drive the simulated robot')[:2]
    with UserSession(tmp_path, robot='hero') as user:
        user.wait_for_robot()
        user.type(f'{first}\nsleep 12\n{second}')
        lines = user.status.read_for(SECONDS)
        assert user.robot.poll() is None, user.log[-2000:]
        seen = [s for s in lines if s.startswith('chassis ')]
        assert len(seen) >= SECONDS / 2.0 * 0.8, lines[-3:]  # a line every 2 s
        unwell = [s for s in seen if 'DESTROYED' in s or 'power off' in s
                  or 'offline -' not in s or 'hp 300/300' not in s]
        assert not unwell, unwell[:3]
        assert any('shooter READY' in s for s in seen), seen[:3]
        assert 1 <= shots(seen[-1]) <= 5 and max(map(shots, seen)) == shots(seen[-1]), seen[-1]
        assert 'referee: ' not in user.log  # nothing the referee did to be said
