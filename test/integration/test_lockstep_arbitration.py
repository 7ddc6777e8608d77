"""Who commands the robot, in lockstep: the operator's remote, a commander, noise (item 3).

rm_manual's plugin publishes under /manual (the ``manual`` source, priority 100);
``robot.publish`` here stands for ``topic pub`` or a planner on the plain topics (the
``external`` source, priority 10). The harness hands the simulated DR16's frames to the
plugin as its reader would; noise goes through the reader's own frame splitter
(``DbusStream``) on the simulated clock.
"""

from __future__ import annotations

import random

import pytest
from geometry_msgs.msg import Twist
from rm_base.hardware.protocols import dbus
from rm_base.hardware.protocols.dbus import Switch
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd

pytestmark = [pytest.mark.ros]

FULL = 660


def chassis(robot):
    return robot.plugin('chassis').state.name


def commander(robot, mode=ChassisCmd.RAW):
    """An external commander streaming mode at 50 Hz, 0.5 m/s forward."""
    vel = Twist()
    vel.linear.x = 0.5
    robot.publish('/chassis_cmd', lambda: ChassisCmd(mode=mode), rate_hz=50.0)
    robot.publish('/vel_cmd', vel, rate_hz=50.0)


def in_charge(robot, topic='/chassis_cmd'):
    mux = robot.host._io.command_mux
    source = mux.in_charge(topic, robot.host.get_clock().now().nanoseconds)
    return source.name if source is not None else ''


def test_noise_on_a_silent_dr16_port_never_commands_and_never_flips_the_commander():
    # The finding: one burst that decoded drove FOLLOW at 1.7 m/s, then rm_manual sent
    # PASSIVE forever and the chassis flipped RAW/PASSIVE every 10 ms.
    with LockstepRobot() as robot:
        commander(robot)
        assert robot.wait_until(lambda: chassis(robot) == 'RAW', 2.0)
        manual = robot.plugin('manual')
        clock = robot.host.get_clock()
        splitter = dbus.DbusStream(clock=lambda: clock.now().nanoseconds)
        rng = random.Random(7)
        seen = []
        bursts = 0

        def noise():
            nonlocal bursts
            if robot.ticks % 7 == 0 and bursts < 10_000:  # a burst every 7 ms: in rhythm
                bursts += 1
                for frame in splitter.feed(rng.randbytes(dbus.FRAME_LENGTH)):
                    manual.on_remote_frame(frame, clock.now().nanoseconds)
            seen.append(chassis(robot))

        robot.run(70.0, every=noise)
        assert bursts == 10_000
        assert set(seen) == {'RAW'}
        assert manual.state.name == 'NO_DATA'
        assert in_charge(robot) == 'external'
        report = robot.host._io.command_mux.report(clock.now().nanoseconds)['/chassis_cmd']
        assert report['taken']['manual'] == 0 and report['yielded']['external'] == 0


def test_the_operator_takes_over_stops_the_robot_and_yields_when_the_remote_is_lost():
    with LockstepRobot() as robot:
        commander(robot)
        assert robot.wait_until(lambda: chassis(robot) == 'RAW', 2.0)
        remote = robot.world.remote
        # the operator's right switch down: an explicit PASSIVE, above the commander
        remote.hold(switch_a=Switch.DOWN, switch_b=Switch.DOWN)
        remote.switch_on()
        assert robot.wait_until(lambda: chassis(robot) == 'PASSIVE', 0.5)
        assert in_charge(robot) == 'manual'
        robot.run(1.0)
        assert chassis(robot) == 'PASSIVE'  # the commander streams on, yielding
        # the sticks: the operator drives (FOLLOW), the commander still yields
        remote.hold(switch_a=Switch.MID, channels=(0, 0, 0, FULL // 2))
        assert robot.wait_until(lambda: chassis(robot) == 'FOLLOW', 0.5)
        # the remote is lost: PASSIVE at once (its stop_time), then the commander again
        remote.switch_off()
        states = []
        robot.run(1.0, every=lambda: states.append(chassis(robot)))
        first_passive = states.index('PASSIVE')
        assert first_passive <= 160  # data_timeout 0.1 s + the plugin's 20 ms tick, ramp
        back = states.index('RAW', first_passive)
        # 0.3 s of PASSIVE, and the manual source's 0.2 s timeout after its last message
        assert 450 <= back <= 700, back
        assert set(states[back:]) == {'RAW'}
        assert in_charge(robot) == 'external'
