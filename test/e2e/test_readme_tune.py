"""README's "Tune it live", typed as written: a live key changes, the others refuse, the
dump starts the next run with the tuned value.
"""

import pytest
import yaml
from support.user_session import UserSession, readme_blocks

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]


def test_a_live_key_is_set_the_others_refuse_and_the_dump_starts_the_next_run(tmp_path):
    tune, restart = readme_blocks('Tune it live')
    with UserSession(tmp_path) as user:
        user.wait_for_robot()
        said = user.type(tune, wait=True, cwd=user.workdir(), timeout=120.0)
        assert '  shooter.max_hz' in said.splitlines(), said
        assert ('    Additional constraints: type: double; unit: shots/s; > 0.0; required; '
                'set while running') in said.splitlines(), said
        assert said.count('Set parameter successful') == 1, said
        assert ('rmcli: error: Setting parameter failed: shooter.max_hz must be > 0.0, '
                'got -1.0') in said, said
        assert ('rmcli: error: Setting parameter failed: Trying to set a read-only '
                'parameter: shooter.slots.') in said, said
        assert 'set shooter.max_hz = 8.0 (from the next run on)' in user.log
        dumped = yaml.safe_load((user.workdir() / 'tuned.yaml').read_text())
        assert dumped['/rm_robot']['ros__parameters']['shooter']['max_hz'] == 8.0
    # the next run, from the dump: README's own line, in the same folder
    again = tmp_path / 'again'
    again.mkdir()
    command = ['bash', '-c', f'source scripts/env.sh && cd {user.workdir()} && {restart.strip()}']
    with UserSession(again, command=command) as user:
        user.wait_for_robot()
        said = user.type('rmcli param get /rm_robot shooter.max_hz', wait=True)
        assert said == 'Double value is: 8.0\n', said
