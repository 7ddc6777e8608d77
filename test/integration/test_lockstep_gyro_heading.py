"""GYRO's closed heading loop on rm_sim, in lockstep: a dragging wheel does not slow the spin.

The standard robot spins in GYRO at standstill (6 rad/s in standard.yaml); once it is up
to speed, one wheel gets a brake torque larger than its motor can overcome, as a jammed
bearing or a wheel caught on an edge would. Open loop (``gyro.heading.gain: 0``) the
wheels' speed loops keep the other three wheels at their targets and the chassis turns a
quarter slower. With the loop (standard.yaml's gain) the other three wheels are asked for
more until the chassis turns at the spin asked for again.
"""

from __future__ import annotations

import pytest
from geometry_msgs.msg import Twist
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd, GimbalCmd

pytestmark = [pytest.mark.ros]

COMMAND_HZ = 50.0  # [Hz]
SPIN = 6.0  # [rad/s] standard.yaml gyro.spin_rate
DRAG = 8.0  # [N·m] brake torque on wheel_fl's output: more than its motor gives


def spin_rates(gain: float | None) -> tuple[float, float]:
    """The chassis' spin rate [rad/s] before the drag, and over the 4th second after it."""
    overrides = {} if gain is None else {'rm_robot': {'chassis.gyro.heading.gain': gain}}
    with LockstepRobot(plugins=('chassis', 'gimbal'), overrides=overrides) as robot:
        robot.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=COMMAND_HZ)
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.GYRO), rate_hz=COMMAND_HZ)
        robot.publish('/vel_cmd', Twist(), rate_hz=COMMAND_HZ)
        body = robot.world.body
        robot.run(4.0)  # spun up (power-limited), the lag of the spin-up made up
        start = body.yaw
        robot.run(0.5)
        before = (body.yaw - start) / 0.5
        body.wheels[0].model.brake_torque = DRAG
        robot.run(3.0)
        start = body.yaw
        robot.run(1.0)
        return before, body.yaw - start


@pytest.fixture(scope='module')
def open_loop():
    return spin_rates(0.0)


@pytest.fixture(scope='module')
def closed_loop():
    return spin_rates(None)  # the config's loop


def test_both_spin_as_asked_before_the_drag(open_loop, closed_loop):
    assert open_loop[0] == pytest.approx(SPIN, rel=0.01)
    assert closed_loop[0] == pytest.approx(SPIN, rel=0.01)


def test_open_loop_a_dragging_wheel_slows_the_spin(open_loop):
    assert open_loop[1] < 0.8 * SPIN


def test_the_heading_loop_brings_the_spin_back(closed_loop):
    assert closed_loop[1] == pytest.approx(SPIN, rel=0.02)
