"""POSITION mode in lockstep: the standard robot on rm_sim moves by (dx, dy, dyaw) and stops.

Each move is given relative to where the robot stands when its move_id arrives (dx, dy
along base_link's axes then, dyaw from its heading then); the simulated body must end
within a few centimetres (odometry against ground truth) and the plugin say it arrived.
The same command repeated at 50 Hz is one move, and so is the same move_id after a PASSIVE
or a silence (it holds where it stands); a new move_id starts the next one.
"""

from __future__ import annotations

import math

import pytest
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd

pytestmark = [pytest.mark.ros]


def move(dx: float, dy: float, dyaw: float, move_id: int) -> ChassisCmd:
    cmd = ChassisCmd(mode=ChassisCmd.POSITION, move_id=move_id)
    cmd.move_x, cmd.move_y, cmd.move_yaw = dx, dy, dyaw
    return cmd


def test_moves_end_where_they_were_asked_and_hold():
    with LockstepRobot(plugins=('imu', 'gpio', 'chassis', 'gimbal')) as robot:
        chassis, body = robot.plugin('chassis'), robot.world.body
        robot.watch('/chassis_state')
        robot.publish('/chassis_cmd', move(1.0, 0.5, math.pi / 2, 1), rate_hz=50)
        robot.run(0.5)
        assert chassis.state.name == 'POSITION'
        assert chassis.reason == 'commanded POSITION: moving to the goal'
        robot.run(3.5)
        assert chassis.reason == 'commanded POSITION: arrived, holding'
        assert (body.x, body.y) == pytest.approx((1.0, 0.5), abs=0.05)
        assert body.yaw == pytest.approx(math.pi / 2, abs=0.03)
        robot.run(1.0)  # the same move_id again and again: it stays there
        assert (body.x, body.y) == pytest.approx((1.0, 0.5), abs=0.05)
        # back 0.5 m along its own x (the world's y now) and turn back to 0
        robot.publish('/chassis_cmd', move(-0.5, 0.0, -math.pi / 2, 2), rate_hz=50)
        robot.run(4.0)
        assert chassis.reason == 'commanded POSITION: arrived, holding'
        assert (body.x, body.y) == pytest.approx((1.0, 0.0), abs=0.05)
        assert body.yaw == pytest.approx(0.0, abs=0.03)
        state = robot.latest('/chassis_state')
        assert state.state == ChassisCmd.POSITION
        assert max(abs(w) for w in state.wheel_speed) < 0.5  # stopped [rad/s]


def test_a_move_with_a_nan_is_rejected_and_never_moves_the_robot():
    with LockstepRobot(plugins=('imu', 'gpio', 'chassis', 'gimbal')) as robot:
        robot.publish('/chassis_cmd', move(math.nan, 0.0, 0.0, 1), rate_hz=50)
        robot.run(0.5)
        assert robot.plugin('chassis').state.name == 'PASSIVE'
        assert math.hypot(robot.world.body.x, robot.world.body.y) < 1e-3


def test_a_move_that_ran_does_not_run_again_after_a_passive_blip_or_a_silence():
    # The finding: after any PASSIVE blip the robot drove the same move_id again from
    # where it stood (another 1 m and a quarter turn about every 10 s).
    with LockstepRobot(plugins=('imu', 'gpio', 'chassis', 'gimbal')) as robot:
        chassis, body = robot.plugin('chassis'), robot.world.body
        robot.publish('/chassis_cmd', move(1.0, 0.0, 0.0, 7), rate_hz=50)
        robot.run(3.0)
        assert chassis.reason == 'commanded POSITION: arrived, holding'
        assert body.x == pytest.approx(1.0, abs=0.05)
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.PASSIVE), rate_hz=50)
        robot.run(0.3)
        assert chassis.state.name == 'PASSIVE'
        robot.publish('/chassis_cmd', move(1.0, 0.0, 0.0, 7), rate_hz=50)  # the same move
        robot.run(3.0)
        assert chassis.state.name == 'POSITION'
        assert body.x == pytest.approx(1.0, abs=0.05)  # held where it stood
        robot.stop_publishing('/chassis_cmd')  # the commander falls silent, then resumes
        robot.run(1.0)
        robot.publish('/chassis_cmd', move(1.0, 0.0, 0.0, 7), rate_hz=50)
        robot.run(3.0)
        assert body.x == pytest.approx(1.0, abs=0.05)
        robot.publish('/chassis_cmd', move(1.0, 0.0, 0.0, 8), rate_hz=50)  # a new one runs
        robot.run(3.0)
        assert body.x == pytest.approx(2.0, abs=0.05)
