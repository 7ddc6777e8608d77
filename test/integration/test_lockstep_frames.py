"""The robot's TF in lockstep: its frames against rm_sim's ground truth, TRACK in a camera's.

The standard robot drives and turns while the gimbal holds its world heading; the frames
its plugins send (odom -> base_link from the chassis, base_link -> yaw_link -> pitch_link
from the gimbal's joints, the muzzle and camera mounts) must put the muzzle where the
simulated body has it. Then an auto-aim stand-in sends, at 50 Hz, where a point fixed in
the world is seen from the camera (computed from the ground truth), and the barrel must
turn to that point.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from geometry_msgs.msg import Twist
from rm_base.geometry.transforms import SE3
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd, GimbalCmd

pytestmark = [pytest.mark.ros]

COMMAND_HZ = 50.0
WORLD_TARGET = (4.0, 3.0, 0.6)  # [m] in odom: the point the camera "sees"


def twist(x: float = 0.0, wz: float = 0.0) -> Twist:
    msg = Twist()
    msg.linear.x, msg.angular.z = x, wz
    return msg


def true_pose(robot: LockstepRobot, frame: str) -> SE3:
    """frame's pose in odom from the simulated body (the config's pivot and mounts)."""
    b = robot.world.body
    gimbal = robot.plugin('gimbal').config
    mounts = {m.child: m for m in gimbal.frames.mounts}
    pose = (
        SE3.from_translation_rpy((b.x, b.y, 0.0), 0.0, 0.0, b.yaw)
        @ SE3.from_translation_rpy(gimbal.pivot, 0.0, 0.0, b.gimbal_yaw)
        @ SE3.from_translation_rpy((0.0, 0.0, 0.0), 0.0, b.gimbal_pitch, 0.0)
    )
    return pose if frame == gimbal.frames.pitch else pose @ mounts[frame].transform


@pytest.fixture(scope='module')
def robot():
    with LockstepRobot(plugins=('imu', 'gpio', 'chassis', 'gimbal')) as robot:
        robot.watch('/tf', keep_history=True)
        robot.watch('/tf_static', keep_history=True)
        robot.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=COMMAND_HZ)
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=COMMAND_HZ)
        robot.publish('/vel_cmd', twist(x=1.0, wz=0.8), rate_hz=COMMAND_HZ)
        robot.run(2.0)
        yield robot


def test_the_chassis_frame_is_where_the_body_is(robot):
    b = robot.world.body
    found = robot.plugin('chassis').frames.lookup('odom', 'base_link')
    x, y, _ = found.transform.translation
    assert math.hypot(x - b.x, y - b.y) < 0.05  # odometry after a 2 m arc
    assert found.transform.rpy[2] == pytest.approx(b.yaw, abs=0.02)
    assert robot.now_ns - found.stamp_ns <= 10_000_000  # sent at 100 Hz


def test_the_gimbal_frames_follow_its_joints(robot):
    b = robot.world.body
    assert abs(b.gimbal_yaw) > 0.5  # the gimbal held its heading while the chassis turned
    rpy = robot.plugin('gimbal').frames.lookup('base_link', 'pitch_link').transform.rpy
    assert rpy == pytest.approx((0.0, b.gimbal_pitch, b.gimbal_yaw), abs=0.01)


def test_the_muzzle_is_where_the_body_puts_it(robot):
    frames = robot.plugin('gimbal').frames
    muzzle = frames.lookup('odom', 'muzzle').transform.translation
    np.testing.assert_allclose(muzzle, true_pose(robot, 'muzzle').translation, atol=0.05)


def test_tf_carries_each_link_and_tf_static_the_mounts(robot):
    links = {
        (t.header.frame_id, t.child_frame_id) for m in robot.history('/tf') for t in m.transforms
    }
    assert {('odom', 'base_link'), ('base_link', 'yaw_link'), ('yaw_link', 'pitch_link')} <= links
    static = {(t.header.frame_id, t.child_frame_id)
              for m in robot.history('/tf_static') for t in m.transforms}
    assert {('pitch_link', 'muzzle'), ('pitch_link', 'camera_link')} <= static


def aim_error(robot: LockstepRobot) -> tuple[float, float]:
    """Yaw and pitch of the barrel (truth) minus those of the line to WORLD_TARGET [rad]."""
    barrel = true_pose(robot, 'pitch_link')
    sight = barrel.inverse().apply(WORLD_TARGET)  # the target in the barrel's frame
    return math.atan2(sight[1], sight[0]), -math.atan2(sight[2], math.hypot(sight[0], sight[1]))


def test_track_aims_at_a_point_the_camera_sees(robot):
    def detection() -> GimbalCmd:  # where the camera sees the target now
        cmd = GimbalCmd(mode=GimbalCmd.TRACK)
        cmd.target.header.frame_id = 'camera_link'
        x, y, z = (float(v) for v in true_pose(robot, 'camera_link').inverse().apply(WORLD_TARGET))
        cmd.target.point.x, cmd.target.point.y, cmd.target.point.z = x, y, z
        return cmd

    robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.PASSIVE), rate_hz=COMMAND_HZ)
    robot.publish('/gimbal_cmd', detection, rate_hz=COMMAND_HZ)
    before = aim_error(robot)
    robot.run(1.0)
    assert robot.plugin('gimbal').state.name == 'TRACK'
    assert abs(before[0]) > 0.3  # it had to turn
    yaw_error, pitch_error = aim_error(robot)
    assert abs(yaw_error) < 0.02 and abs(pitch_error) < 0.02


def test_a_target_in_an_unknown_frame_is_refused_by_name(robot):
    cmd = GimbalCmd(mode=GimbalCmd.TRACK)
    cmd.target.header.frame_id = 'turret_cam'
    cmd.target.point.x = 3.0
    robot.publish('/gimbal_cmd', cmd, rate_hz=COMMAND_HZ)
    robot.run(0.1)
    gimbal = robot.plugin('gimbal')
    assert gimbal.state.name == 'PASSIVE'
    assert "unknown target frame 'turret_cam' (known: odom, world, base_link, camera_link" in (
        gimbal.reason
    )
