"""When the simulated referee cuts power, one log line and the status line say so.

The standard robot with its heat limit off (`shooter.heat.calibre: 0`, a robot without the
referee system) fires twenty 17 mm shots at its top rate: the barrel passes the referee's
heat limit and the referee locks the launcher (its 24 V output off). rm_robot's log must say
it once (not once per 10 Hz report), the status line must show it, and README's
`/rm_sim/referee/reset` must bring the robot back, said once too.
"""

import pytest
from support.user_session import UserSession, readme_blocks

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

FIRE = """
rmcli topic pub /shoot_cmd rm_msgs/msg/ShootCmd '{header: auto, mode: PUSH, speed: 15.0, \
hz: 20.0, num: 20, burst_id: 1}' -r 20 -p 0 &
"""


def test_a_locked_launcher_is_said_once_and_the_reset_service_revives_the_robot(tmp_path):
    overrides = tmp_path / 'no_heat_limit.yaml'
    # command_timeout 1 s: a stall of the publisher (0.3 s seen under CPU steal) must not
    # end the burst, which a blip never restarts; the referee's cut is what is tested here
    overrides.write_text('rm_robot:\n  ros__parameters:\n    shooter.heat.calibre: 0\n'
                         '    shooter.command_timeout: 1.0\n')
    command = ['scripts/with_env.sh', 'bringup', '--robot', 'standard', '--sim',
               '--params-file', str(overrides)]
    with UserSession(tmp_path, command=command) as user:
        user.wait_for_robot()
        assert 'hp 200/200' in user.status.wait_for(lambda s: 'hp ' in s)
        user.type(FIRE)
        cut = user.status.wait_for(lambda s: 'power off shooter' in s)
        assert cut, user.status.lines[-3:]
        user.status.read_for(3.0)  # thirty more reports of the referee, still off
        assert user.log.count('referee: power off at shooter') == 1, user.log[-3000:]
        (reset,) = readme_blocks('The referee system')
        said = user.type(reset, wait=True)
        assert 'success=True' in said and 'robot revived' in said, said
        back = user.status.wait_for(lambda s: 'hp 200/200' in s and 'power off' not in s)
        assert back, user.status.lines[-3:]
        assert user.log.count('referee: power back at shooter') == 1, user.log[-3000:]
