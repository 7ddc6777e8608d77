"""The swerve robot in lockstep on rm_sim: a square, a reversal, and GYRO while translating.

rm_bringup's swerve config and its simulation overlay, stepped tick by tick with the
simulator (support.lockstep): the modules point where the steering motors turn them, so
the body goes where the plugin steers it, and every run gives the same numbers.
"""

from __future__ import annotations

import itertools
import math

import pytest
from geometry_msgs.msg import Twist
from rm_base.joints import Mode
from rm_base.sim import Fault
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd

pytestmark = [pytest.mark.ros]

STEERS = ('steer_fl', 'steer_fr', 'steer_rl', 'steer_rr')
WHEELS = ('wheel_fl', 'wheel_fr', 'wheel_rl', 'wheel_rr')


def move(dx: float, dy: float, dyaw: float, move_id: int) -> ChassisCmd:
    cmd = ChassisCmd(mode=ChassisCmd.POSITION, move_id=move_id)
    cmd.move_x, cmd.move_y, cmd.move_yaw = dx, dy, dyaw
    return cmd


def twist(x: float = 0.0, y: float = 0.0, wz: float = 0.0) -> Twist:
    msg = Twist()
    msg.linear.x, msg.linear.y, msg.angular.z = x, y, wz
    return msg


def steering(robot: LockstepRobot) -> list[float]:
    return [robot.joint(name)['position'] for name in STEERS]


def test_a_one_metre_square_ends_where_it_began_and_no_module_turns_past_90_degrees():
    with LockstepRobot('swerve', plugins=('chassis',)) as robot:
        chassis, body = robot.plugin('chassis'), robot.world.body
        targets: list[tuple[float, ...]] = []
        path: list[tuple[float, float, float]] = []

        def sample() -> None:
            path.append((body.x, body.y, body.yaw))
            if chassis._swerve is not None and chassis.state.name == 'POSITION':
                targets.append(chassis._swerve.steer_targets)

        corners = [(1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0)]
        sides = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]
        for move_id, ((dx, dy), corner) in enumerate(zip(sides, corners, strict=True), 1):
            robot.publish('/chassis_cmd', move(dx, dy, 0.0, move_id), rate_hz=50)
            start = len(path)
            robot.run(3.0, every=sample)
            assert chassis.reason == 'commanded POSITION: arrived, holding', move_id
            assert (body.x, body.y) == pytest.approx(corner, abs=0.03), move_id
            assert body.yaw == pytest.approx(0.0, abs=0.02), move_id
            # along the side: never more than 5 cm off the straight line between corners
            off = [abs(y - corner[1]) if dx else abs(x - corner[0])
                   for x, y, _ in path[start:]]
            assert max(off) < 0.05, (move_id, max(off))
        # each corner turns the modules by 90 degrees at most, in one steering target
        steps = [max(abs(b - a) for a, b in zip(p, q, strict=True))
                 for p, q in itertools.pairwise(targets)]
        assert max(steps) <= math.pi / 2 + 1e-9
        # the modules' measured angles followed their targets
        assert steering(robot) == pytest.approx(list(targets[-1]), abs=0.02)


def test_reversing_flips_the_wheels_instead_of_turning_the_modules_round():
    with LockstepRobot('swerve', plugins=('chassis',)) as robot:
        body = robot.world.body
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=50)
        robot.publish('/vel_cmd', twist(y=0.8), rate_hz=50)  # sideways: modules to 90 deg
        robot.run(1.5)
        assert body.twist[1] == pytest.approx(0.8, abs=0.02)
        assert steering(robot) == pytest.approx([math.pi / 2] * 4, abs=0.02)
        robot.publish('/vel_cmd', twist(y=-0.8), rate_hz=50)  # and back
        robot.run(1.5)
        assert body.twist[1] == pytest.approx(-0.8, abs=0.02)
        assert steering(robot) == pytest.approx([math.pi / 2] * 4, abs=0.02)
        # joint velocities: along each module's direction (the bridge applies the mirroring)
        assert all(robot.joint(w)['velocity'] < -10.0 for w in WHEELS)


def test_gyro_translates_along_odom_while_spinning():
    with LockstepRobot('swerve', plugins=('chassis',)) as robot:
        body = robot.world.body
        gyro = ChassisCmd(mode=ChassisCmd.GYRO, follow_source='odom')
        robot.publish('/chassis_cmd', gyro, rate_hz=50)
        robot.publish('/vel_cmd', twist(x=1.0), rate_hz=50)
        robot.run(1.0)
        x0, y0, yaw0 = body.x, body.y, body.yaw
        robot.run(2.0)
        # spinning at 6 - (6 - 4) * 1.0 / 1.5 rad/s (gyro.spin_rate 6 at rest, linear down to
        # translating_spin_rate 4 at translating_speed 1.5 m/s) ...
        assert (body.yaw - yaw0) / 2.0 == pytest.approx(6.0 - 2.0 / 1.5, abs=0.1)
        # ... while the body goes along odom's x at 1 m/s (chassis.latency 0.02 s looks the
        # translation ahead by the command's latency: with 0 it curves 0.21 m off here)
        assert body.x - x0 == pytest.approx(2.0, abs=0.05)
        assert abs(body.y - y0) < 0.05


def test_a_steering_joint_that_goes_offline_makes_the_chassis_passive_and_every_joint_limp():
    with LockstepRobot('swerve', plugins=('chassis',)) as robot:
        chassis = robot.plugin('chassis')
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=50)
        robot.publish('/vel_cmd', twist(y=0.5), rate_hz=50)
        robot.run(1.0)
        assert chassis.state.name == 'RAW'
        assert robot.joint('steer_fl')['mode'] == Mode.POSITION
        robot.world.inject('steer_rl', Fault.offline())
        robot.run(0.3)  # past the feedback timeouts (0.1 s)
        assert chassis.state.name == 'PASSIVE'
        assert chassis.reason == (
            "steering joint 'steer_rl' has no fresh feedback (offline or stale)"
        )
        assert all(robot.joint(j)['mode'] == Mode.OFF for j in (*WHEELS, *STEERS))
        # back online: driving again, the modules steered from where they stand
        robot.world.clear_faults('steer_rl')
        robot.run(1.5)
        assert chassis.state.name == 'RAW'
        assert robot.world.body.twist[1] == pytest.approx(0.5, abs=0.02)
