"""`rmcli teleop` onto the command topics, and rm_sim's receiver input (/rm_sim/remote).

teleop runs in a pseudo-terminal (it reads keys); a node of the test's hears what it
sends. The receiver input is rm_base.bridge.sim_remote on a stepped world with a remote.
"""

from __future__ import annotations

import sys

import pytest
from geometry_msgs.msg import Twist
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rm_base.bridge.sim_remote import TRANSMITTER_LOST_S, SimRemoteInput
from rm_base.hardware.protocols.dbus import DbusFrame, Key, Switch
from rm_base.sim import SimWorld
from support.ros import wait_until
from support.terminal import Terminal
from support.user_session import user_environment

from rm_msgs.msg import ChassisCmd, GimbalCmd, RemoteInput, ShootCmd

pytestmark = pytest.mark.ros

WAIT_S = 30.0  # discovery and a start under CPU steal: generous


def test_without_sim_the_mapping_runs_in_teleop_and_its_commands_go_to_the_topics(test_node):
    node, executor = test_node
    vel, chassis, shoot = [], [], []
    node.create_subscription(Twist, '/vel_cmd', vel.append, 10)
    node.create_subscription(ChassisCmd, '/chassis_cmd', chassis.append, 10)
    node.create_subscription(ShootCmd, '/shoot_cmd', shoot.append, 10)
    # a robot subscribes all four: teleop takes keys once each of its topics has a subscriber
    node.create_subscription(GimbalCmd, '/gimbal_cmd', lambda _m: None, 10)
    keyboard = Terminal(f'exec {sys.executable} -m rm_bringup.cli teleop', user_environment())
    try:
        assert wait_until(lambda: chassis, WAIT_S, spin=executor.spin_once), keyboard.screen
        assert chassis[-1].mode == ChassisCmd.FOLLOW  # the keyboard's mode: nothing held
        keyboard.hold(b'W', 1.0)  # capital: SHIFT held, the FAST gear
        # (the test spins after the key is let go: what came while it was held)
        assert wait_until(
            lambda: any(v.linear.x == 2.0 for v in vel)
            and any(c.speed_gear == ChassisCmd.GEAR_FAST for c in chassis),
            WAIT_S, spin=executor.spin_once), keyboard.screen[-500:]
        keyboard.tap(b'r')
        assert wait_until(lambda: any(m.mode == ShootCmd.READY for m in shoot), WAIT_S,
                          spin=executor.spin_once), keyboard.screen[-500:]
    finally:
        code = keyboard.close()
    assert code == 0, keyboard.screen[-500:]
    wait_until(lambda: False, 0.5, spin=executor.spin_once)
    assert (chassis[-1].mode, shoot[-1].mode) == (ChassisCmd.PASSIVE, ShootCmd.PASSIVE)
    assert 'teleop -> /chassis_cmd, /vel_cmd, /gimbal_cmd, /shoot_cmd' in keyboard.screen


@pytest.fixture
def world(tmp_path):
    config = {'timing': 'stepped', 'channels': {'teleop_test': []},
              'remote': {'path': str(tmp_path / 'dr16')}}
    with SimWorld.from_config(config) as w:
        yield w


def test_rm_sim_sends_what_arrives_refuses_what_a_frame_cannot_carry_and_goes_silent(
        test_node, world):
    node, executor = test_node
    receiver = SimRemoteInput(node, world, prefix='~/')
    publisher = node.create_publisher(
        RemoteInput, '~/remote', QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
    held = RemoteInput(channels=[660, 0, 0, -12], switch_a=RemoteInput.SWITCH_UP,
                       switch_b=RemoteInput.SWITCH_MID, mouse_x=40, keys=int(Key.W))

    def delivered(msg, count):
        def sent():
            publisher.publish(msg)
            return receiver.accepted + receiver.rejected >= count
        return wait_until(sent, WAIT_S, spin=executor.spin_once, period=0.02)

    assert not world.remote.on
    assert delivered(held, 1)
    assert world.remote.on
    expected = DbusFrame((660, 0, 0, -12), Switch.UP, Switch.MID, (40, 0, 0), keys=int(Key.W))
    assert world.remote.state == expected
    bad = RemoteInput(switch_a=0, switch_b=RemoteInput.SWITCH_MID)  # no switch position
    assert delivered(bad, receiver.accepted + 1 + receiver.rejected)
    assert receiver.rejected >= 1
    assert world.remote.state == expected  # kept
    beyond = RemoteInput(channels=[700, 0, 0, 0], switch_a=1, switch_b=1)
    rejected = receiver.rejected
    assert delivered(beyond, receiver.accepted + rejected + 1)
    assert receiver.rejected > rejected and world.remote.state == expected
    # the transmitter stops: the receiver goes silent
    assert wait_until(lambda: not world.remote.on, TRANSMITTER_LOST_S + WAIT_S,
                      spin=executor.spin_once, period=0.05)
    assert not receiver.on
