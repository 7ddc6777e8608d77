"""README's "Super-capacitor", typed as written: its YAML saved, the robot started with it.

The status line shows the simulated board ready, then a burst once the commander asks for
more than the referee's limit.
"""

import re
import shutil

import pytest
import yaml
from support.user_session import ROOT, UserSession, readme_blocks, readme_yaml

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]


def test_the_board_is_ready_and_a_burst_shows_on_the_status_line(tmp_path):
    start, burst = readme_blocks('Super-capacitor')
    work = tmp_path / 'work'
    work.mkdir()
    (work / 'supercap.yaml').write_text(yaml.safe_dump(readme_yaml('Super-capacitor')))
    (work / 'scripts').symlink_to(ROOT / 'scripts')
    command = ['bash', '-c', f'cd {work} && ' + ' && '.join(
        line for line in start.strip().splitlines() if not line.startswith('#'))]
    with UserSession(tmp_path, command=command) as user:
        user.wait_for_robot()
        ready = user.status.wait_for(lambda s: 'cap 100% ready' in s, 30.0)
        assert ready, user.status.lines[-3:]
        user.type(burst)
        bursting = user.status.wait_for(lambda s: re.search(r'cap \d+% burst', s), 30.0)
        assert bursting and 'chassis GYRO' in bursting, user.status.lines[-3:]
        assert 'offline -' in bursting, bursting  # every motor answers; nothing was cut
    shutil.rmtree(work, ignore_errors=True)
