"""The client UI on the standard robot, in lockstep, drawn on rm_sim's referee client.

README's "Client UI" config (read from README) loads the plugin beside the others, with
README's super-capacitor; the robot drives GYRO with the shooter READY. rm_sim's client
must show every figure the layout wants, with no error and within the link's limits;
once the robot stands still nothing more is sent but the periodic redraw; a client that
restarts shows everything again within the redraw period.
"""

from __future__ import annotations

import pytest
from geometry_msgs.msg import Twist
from support.lockstep import LockstepRobot
from support.user_session import readme_yaml

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

pytestmark = [pytest.mark.ros]

COMMAND_HZ = 50.0
REFRESH_S = 5.0  # standard.yaml ui.refresh_s


def robot() -> LockstepRobot:
    plugins = readme_yaml('Client UI')['rm_robot']['ros__parameters']['plugins']
    supercap = readme_yaml('Super-capacitor')['can_bridge']['ros__parameters']['supercap']
    return LockstepRobot(plugins=(*plugins, 'manual'), overrides={
        'can_bridge': {f'supercap.{k}': v for k, v in supercap.items()}})


def test_the_client_shows_the_robot_only_changes_go_out_and_a_restarted_client_is_redrawn():
    with robot() as r:
        client = r.world.referee.client
        r.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=COMMAND_HZ)
        r.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.READY, speed=15.0), rate_hz=COMMAND_HZ)
        r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.GYRO), rate_hz=COMMAND_HZ)
        r.publish('/vel_cmd', Twist(), rate_hz=COMMAND_HZ)
        r.run(4.0)
        shown = client.shown
        assert shown[b'CMD'].text.startswith('GYRO '), shown.get(b'CMD')
        assert shown[b'FRI'].text == 'FRIC ON READY', shown.get(b'FRI')
        assert {b'CPO', b'CPB', b'CPN', b'HTO', b'HTB', b'AMH', b'AMV', b'AMC'} <= set(shown)
        assert shown[b'CPN'].figure.details_c > 90  # the capacitor about full (a %)
        # standing still, only the redraw goes out: at most a redraw's frames in 2 s
        r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.PASSIVE), rate_hz=COMMAND_HZ)
        r.run(1.0)
        before = client.frames
        r.run(2.0)
        assert client.frames - before <= 4, client.frames - before
        # a client that restarts is drawn again within the redraw period
        wanted = dict(client.shown)
        client.reconnect()
        r.run(REFRESH_S + 1.5)
        assert set(client.shown) == set(wanted)
        assert not client.errors, client.errors
        assert client.peak_frames_per_s <= 10 and client.peak_bytes_per_s <= 3720
        assert r.interaction.stats.dropped == 0
