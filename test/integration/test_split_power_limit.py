"""The robot split in two processes' layout: the chassis' power stage runs in the bridge.

Real time (a smoke test with generous bounds): rm_robot and can_bridge in this process
but talking over DDS only (``SimRobot(split=True)``), as ``split:=true`` lays them out.
Before the bridge ran the stage, the chassis closed its wheel speed loops over DDS at its
200 Hz; after each speed step the wheel currents swung for longer than the bench's 50 ms
baseline window (bench section 6: 0 of 40 steps settled, now 40 of 40).
"""

from __future__ import annotations

import time

import pytest
from geometry_msgs.msg import Twist
from rm_base.joints import MODE_VELOCITY
from support.robot import SimRobot
from support.ros import wait_until

from rm_msgs.msg import ChassisCmd, ChassisState

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 15.0  # [s] longest wait for a condition
AT_REST_S = 1.0  # how long the wheels are watched at rest [s]
# |effort| a wheel at rest may show: friction and the ramp's last steps, far under the
# M3508's 4.8 N·m (20 A) the oscillation reached
QUIET_EFFORT = 0.5  # [N·m]


@pytest.fixture
def robot():
    robot = SimRobot('standard', plugins=['chassis'], split=True)
    robot.subscribe('/chassis_state', ChassisState)
    yield robot
    robot.close()


def test_the_bridge_runs_the_chassis_power_stage_and_the_wheels_rest_quietly(robot):
    hw = robot.bridge.hardware
    chassis = robot.plugin('chassis')
    assert wait_until(lambda: 'chassis' in hw.power_limits, WAIT), 'no stage from /power_limit'
    assert hw.power_limits['chassis'].joints == tuple(chassis.config.wheel_joints)

    robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW, power_limit=45.0), rate_hz=50.0)
    robot.publish('/vel_cmd', Twist(), rate_hz=50.0)
    assert wait_until(lambda: hw.power_limits['chassis'].limit_w == 45.0, WAIT)
    assert wait_until(
        lambda: (s := robot.latest('/chassis_state')) and s.state == ChassisCmd.RAW, WAIT
    )
    wheels = chassis.config.wheel_joints
    # the wheels get speed targets: their loops run in the bridge at 1 kHz, not over DDS
    assert wait_until(lambda: all(robot.joint(w)['mode'] == MODE_VELOCITY for w in wheels), WAIT)
    worst = 0.0
    end = time.monotonic() + AT_REST_S
    while time.monotonic() < end:
        worst = max(worst, *(abs(robot.joint(w)['effort']) for w in wheels))
        time.sleep(0.005)
    assert worst < QUIET_EFFORT, f'a wheel at rest pushed {worst:.2f} N·m'
