"""The standard robot over the kernel's CAN, in lockstep: the bridge's buses on vcan
(python-can's socketcan, the kernel's queues), the simulated motors answering on the same
interfaces (``sim.can: socketcan``), every tick settled before the next
(docs/KERNEL_CAN.md, "Lockstep over the kernel").

The robot must do over the kernel exactly what it does on rm_sim's own channels: the
same numbers, bit for bit. A link taken down mid-run: nothing reaches the motors on it,
/diagnostics says so, and the robot drives again after the link is back.
"""

from __future__ import annotations

import math

import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Twist
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

from .conftest import ip

pytestmark = [pytest.mark.ros]

COMMAND_HZ = 50.0  # [Hz] as a live commander streams
OK, ERROR = DiagnosticStatus.OK, DiagnosticStatus.ERROR  # bytes, as the message has them


def on_vcan(can0: str, can1: str) -> dict[str, dict[str, object]]:
    """The overrides that put the standard robot's buses and motors on two vcans."""
    return {'can_bridge': {
        'sim.can': 'socketcan',
        'buses.can0.channel': can0,
        'buses.can1.channel': can1,
    }}


def twist(x: float = 0.0) -> Twist:
    msg = Twist()
    msg.linear.x = x
    return msg


def scenario(overrides: dict[str, dict[str, object]] | None) -> dict[str, object]:
    """RAW ahead, GYRO while translating, a burst of three; the numbers each phase ends with."""
    out: dict[str, object] = {}
    with LockstepRobot(overrides=overrides) as robot:
        robot.watch('/shooter_state')
        robot.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=COMMAND_HZ)
        robot.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.PASSIVE), rate_hz=COMMAND_HZ)
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=COMMAND_HZ)
        robot.publish('/vel_cmd', twist(1.0), rate_hz=COMMAND_HZ)
        robot.run(1.5)
        b = robot.world.body
        out['raw'] = (b.x, b.y, b.yaw)
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.GYRO), rate_hz=COMMAND_HZ)
        robot.run(1.0)
        out['gyro'] = (b.x, b.y, b.yaw, b.yaw + b.gimbal_yaw)
        robot.publish('/vel_cmd', twist(), rate_hz=COMMAND_HZ)
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.PASSIVE), rate_hz=COMMAND_HZ)
        robot.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.READY, speed=15.0),
                      rate_hz=COMMAND_HZ)
        robot.run(1.5)
        fired = robot.latest('/shooter_state').shots_fired
        robot.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.PUSH, speed=15.0, hz=5.0, num=3,
                                             burst_id=1), rate_hz=COMMAND_HZ)
        robot.run(1.2)
        out['shots'] = robot.latest('/shooter_state').shots_fired - fired
        out['trigger'] = robot.joint('trigger')['position']
        if overrides is not None:
            stats = robot.bridge.hardware.diagnostics()['buses']
            out['bus_errors'] = sum(s.send_errors + s.receive_errors for s in stats.values())
    return out


def test_the_robot_over_vcan_does_what_it_does_on_rm_sim_bit_for_bit(vcan2):
    kernel = scenario(on_vcan(*vcan2))
    assert kernel.pop('bus_errors') == 0
    assert kernel == scenario(None)
    x, y, yaw = kernel['raw']
    assert 0.9 < x < 1.5 and abs(y) < 0.02 and abs(yaw) < 0.02  # 1 m/s less the ramp
    _, _, spun, heading = kernel['gyro']
    assert abs(spun) > 1.0  # the chassis spins ...
    assert abs(heading) < 0.1  # ... under a gimbal that holds its heading
    assert kernel['shots'] == 3


def status(robot: LockstepRobot, name: str):
    msg = robot.bridge.diagnostics_message()
    return next(s for s in msg.status if s.name.endswith(name))


def test_a_link_down_mid_run_holds_its_motors_is_reported_and_driving_resumes(vcan2):
    can0, _ = vcan2
    with LockstepRobot(overrides=on_vcan(*vcan2)) as robot:
        peer = robot.bridge.sim_peer
        robot.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=COMMAND_HZ)
        robot.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.PASSIVE), rate_hz=COMMAND_HZ)
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=COMMAND_HZ)
        robot.publish('/vel_cmd', twist(1.0), rate_hz=COMMAND_HZ)
        robot.run(1.0)
        assert robot.world.motor('wheel_fl').model.velocity > 10.0

        ip('link', 'set', 'down', can0)
        robot.run(0.05)
        heard = peer.endpoints[can0].received
        robot.run(0.5)
        # nothing reached the motors on the link; they went limp on their own timeout
        assert peer.endpoints[can0].received == heard
        wheel = robot.world.motor('wheel_fl').model
        assert wheel.current == 0.0
        bus = status(robot, 'bus can0')
        assert bus.level == ERROR and 'down' in bus.message, bus.message
        joint = status(robot, 'joint wheel_fl')
        assert joint.level != OK, joint.message
        x_down = robot.world.body.x

        ip('link', 'set', 'up', can0)
        # the bus reopens on its real-time back-off; then the joints clear on fresh feedback
        assert robot.wait_until(lambda: status(robot, 'bus can0').level == OK, timeout=5.0), \
            status(robot, 'bus can0').message
        assert robot.wait_until(lambda: wheel.velocity > 10.0, timeout=3.0)
        assert peer.endpoints[can0].received > heard
        robot.run(0.5)
        assert robot.world.body.x > x_down + 0.3  # driving again
        assert math.isfinite(robot.world.body.x)
