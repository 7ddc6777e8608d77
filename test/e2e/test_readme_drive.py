"""README's "Drive the simulated robot", typed as written: `make run`, then its command blocks.

The blocks are read out of README.md (not copied here) and run by bash in one session, as a
user types them into a second terminal, with README's `source scripts/env.sh` first; the
status lines of `make run` (one every 2 s without a terminal) must say what README says.
Real time, real executables; bounds are generous: the robot needs seconds, the test allows
a minute.
"""

import re
import time

import pytest
from support.user_session import UserSession, readme_blocks, shots

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]


def test_the_drive_examples_do_what_readme_says(tmp_path):
    first, second = readme_blocks('Drive the simulated robot')[:2]
    assert 'mode: GYRO' in first and 'mode: POSITION' in second  # the README we test
    with UserSession(tmp_path) as user:
        user.wait_for_robot()
        # the second terminal: the first block, a look at the robot, the second block
        user.type(f'{first}\nsleep 12\n{second}')
        status = user.status
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
            assert 'PUSH -> PASSIVE: no command on /shoot_cmd' in user.log, status.lines[-3:]
            assert any('chassis POSITION' in s for s in status.lines), status.lines[-3:]
            assert 1 <= max(map(shots, status.lines)) <= 5, status.lines[-3:]
            return
        assert shots(line) == 5, line
        time.sleep(3.0)
        later = status.wait_for(lambda s: s.startswith('chassis '))
        assert later and shots(later) == 5, later  # five, not more
