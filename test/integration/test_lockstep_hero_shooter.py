"""The hero's 42 mm shooter against the simulated referee, in lockstep: one model of a shot.

The finding: on `ROBOT=hero make run` the simulated referee counted 48 shots while
/shooter_state said 0, ran the barrel's heat far over its limit and destroyed the robot.
A shot is a pocket of the trigger pushed past the firing point with the friction wheels
at speed (rm_base.sim.launcher); the shooter counts the slot steps it made (its ball
switch). Here both counts, and the referee's, must agree through README's examples: READY,
then a burst of five, then READY again while the chassis spins.
"""

from __future__ import annotations

import pytest
from geometry_msgs.msg import Twist
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

pytestmark = [pytest.mark.ros]

HZ = 20.0  # README streams its commands at 20 Hz


def test_the_referee_the_launcher_and_the_shooter_count_the_same_shots():
    with LockstepRobot('hero') as r:
        r.watch('/shooter_state')
        rules, launcher = r.world.referee.rules, r.world.body.launcher
        allowance = rules.allowance
        r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.GYRO), rate_hz=HZ)
        r.publish('/vel_cmd', Twist(), rate_hz=HZ)
        r.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=HZ)
        r.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.READY, speed=15.0), rate_hz=HZ)
        r.run(8.0)
        assert launcher.shots == rules.shots == r.latest('/shooter_state').shots_fired == 0
        r.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.PUSH, speed=15.0, hz=5.0, num=5,
                                         burst_id=1), rate_hz=HZ)
        r.run(12.0)
        fired = r.latest('/shooter_state').shots_fired
        assert (launcher.shots, rules.shots, fired, allowance - rules.allowance) == (5, 5, 5, 5)
        r.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.READY, speed=15.0), rate_hz=HZ)
        r.run(10.0)
        assert (launcher.shots, r.latest('/shooter_state').shots_fired) == (5, 5)
        assert rules.hp == rules.settings.max_hp and rules.outputs.shooter
        assert launcher.duds == 0
