"""``sim.can``: the simulated motors answer on a python-can interface the robot's buses open
too (socketcan's vcan on a robot's kernel: test/kernel; here python-can's own virtual
interface, which hands a frame to every other bus on the channel as the kernel does).

In lockstep the robot must do exactly what it does on rm_sim's own channels; in real time
the motors answer through the peer's reader threads.
"""

from __future__ import annotations

import pytest
from geometry_msgs.msg import Twist
from support.lockstep import LockstepRobot
from support.robot import SimRobot

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

pytestmark = [pytest.mark.ros]

COMMAND_HZ = 50.0  # [Hz]


def drive(overrides):
    """RAW ahead 1 s, then GYRO 0.5 s; the body and a wheel's state each phase ends with."""
    with LockstepRobot(overrides=overrides) as robot:
        robot.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=COMMAND_HZ)
        robot.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.PASSIVE), rate_hz=COMMAND_HZ)
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=COMMAND_HZ)
        ahead = Twist()
        ahead.linear.x = 1.0
        robot.publish('/vel_cmd', ahead, rate_hz=COMMAND_HZ)
        robot.run(1.0)
        b = robot.world.body
        raw = (b.x, b.y, b.yaw, robot.joint('wheel_fl')['velocity'])
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.GYRO), rate_hz=COMMAND_HZ)
        robot.run(0.5)
        peer = robot.bridge.sim_peer
        heard = None if peer is None else sum(e.received for e in peer.endpoints.values())
        return raw, (b.x, b.y, b.yaw, b.gimbal_yaw), heard


def test_in_lockstep_the_robot_on_a_can_interface_matches_rm_sim_bit_for_bit():
    raw, gyro, heard = drive({'can_bridge': {'sim.can': 'virtual'}})
    assert heard > 1000  # the motors' commands went over the interface
    assert (raw, gyro) == drive(None)[:2]
    assert 0.6 < raw[0] < 1.0 and abs(gyro[2]) > 0.3


def test_in_real_time_the_motors_answer_through_the_peer():
    with SimRobot(overrides={'can_bridge': {'sim.can': 'virtual'}}) as robot:
        peer = robot.bridge.sim_peer
        assert peer is not None and not peer.stepped
        assert robot.wait_until(
            lambda: all(s['online'] for s in map(robot.joint, robot.bridge.hardware.joint_names)),
            timeout=20.0,
        )
        assert robot.wait_until(
            lambda: min(e.received for e in peer.endpoints.values()) > 100, timeout=20.0
        )
