"""rm_plugins/ManualControl in rm_robot, in real time: DR16 bytes on a pty -> command topics.

The test streams DBUS frames into a pseudo-terminal every 14 ms as a receiver does (the
plugin reads it at 100000 baud 8E1 and splits frames at the silences), and an image link's
0x0304 keyboard frames into a second one; it watches the four command topics over DDS, as
any node would. A smoke test with generous waits: the mapping itself is judged in lockstep
(test_lockstep_manual) and in the unit tests.
"""

import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from rm_base.hardware.protocols import dbus
from rm_base.hardware.protocols import referee as ref
from rm_plugins.serial import LinkState
from support.hosted import HostedPlugins
from support.ros import wait_until
from support.serial_port import Pty, Streamer

from rm_msgs.msg import ChassisCmd, GimbalCmd, PluginState, ShootCmd

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 10.0  # longest wait for any condition [s]; normally met in well under a second


class Harness(HostedPlugins):
    def __init__(self, context, dr16, image_link):
        super().__init__(context, {
            'plugins': ['manual'],
            'manual.type': 'rm_plugins/ManualControl',
            'manual.rate': 50.0,
            'manual.dr16.port': dr16,
            'manual.image_link.port': image_link,
        })
        self.chassis = self.collect(ChassisCmd, '/manual/chassis_cmd')
        self.vel = self.collect(Twist, '/manual/vel_cmd')
        self.gimbal = self.collect(GimbalCmd, '/manual/gimbal_cmd')
        self.shoot = self.collect(ShootCmd, '/manual/shoot_cmd')
        self.states = self.collect(PluginState, '/rm_robot/manual/state', 10)
        self.diagnostics = self.collect(DiagnosticArray, '/diagnostics')
        self.start()

    def state(self):
        return LinkState(self.states[-1].state) if self.states else None


@pytest.fixture
def rig(ros_context, tmp_path):
    dr16, link = Pty(str(tmp_path / 'dr16')), Pty(str(tmp_path / 'link'))
    remote = dbus.DbusFrame(switch_a=dbus.Switch.UP, keys=int(dbus.Key.W))
    streamer = Streamer(lambda: dbus.encode(remote), period=dbus.FRAME_PERIOD_S)
    harness = Harness(ros_context, dr16.path, link.path)
    yield harness, dr16, link, streamer
    streamer.stop()
    harness.close()
    dr16.close()
    link.close()


def silent_for(messages, seconds):
    """No message came for seconds (real time)."""
    count = len(messages)
    time.sleep(seconds)
    return len(messages) == count


def test_the_remote_and_the_image_links_keyboard_become_commands_and_silence_stops_them(rig):
    h, dr16, link, streamer = rig
    assert wait_until(lambda: h.state() is LinkState.NO_DATA, WAIT)
    assert h.chassis == []  # nothing heard: nothing commanded
    streamer.start(dr16)
    # keyboard mode (right switch up), W held on the remote's PC port: 2 m/s forward. Each
    # topic is its own DDS stream, so each is waited for: one may arrive before another.
    assert wait_until(lambda: (
        h.vel and h.vel[-1].linear.x == pytest.approx(2.0)
        and h.chassis and h.chassis[-1].mode == ChassisCmd.FOLLOW
        and h.gimbal and h.gimbal[-1].mode == GimbalCmd.RATE
    ), WAIT), (h.vel[-1:], h.chassis[-1:], h.gimbal[-1:])
    assert h.state() is LinkState.STREAMING
    # the image link adds A (left) and a mouse moving left
    keys = ref.KeyboardMouse(-50, 0, 0, False, False, int(dbus.Key.A))

    def sent(frame):
        # again until heard: pyserial flushes what came before it opened the link's port
        link.write(frame)
        return h.vel[-1].linear.y == pytest.approx(2.0)

    assert wait_until(
        lambda: sent(ref.encode_frame(*ref.encode_status(keys, ref.ProtocolVersion.V2025))), WAIT
    )
    assert wait_until(lambda: h.gimbal[-1].rate_yaw == pytest.approx(1.0), WAIT), h.gimbal[-1]
    # a 2025+ A9 53 frame on the same link: CTRL (the SLOW gear) + F (GYRO)
    v1 = bytes.fromhex('A9 53 94 06 20 AF D8 A2 60 19 F9 FF 0F 00 00 00 01 20 02 DE 1C')
    link.write(v1)
    assert wait_until(lambda: h.chassis[-1].mode == ChassisCmd.GYRO, WAIT)
    assert h.chassis[-1].speed_gear == ChassisCmd.GEAR_SLOW
    assert h.vel[-1].linear.x == pytest.approx(2.0)  # unchanged since W
    # the remote goes silent: everything PASSIVE...
    streamer.stop()
    assert wait_until(lambda: (
        h.chassis[-1].mode == ChassisCmd.PASSIVE
        and h.shoot and h.shoot[-1].mode == ShootCmd.PASSIVE
        and h.gimbal[-1].mode == GimbalCmd.PASSIVE and h.vel[-1].linear.x == 0.0
    ), WAIT), (h.chassis[-1], h.shoot[-1:], h.gimbal[-1], h.vel[-1])
    assert wait_until(lambda: h.state() is LinkState.NO_DATA, WAIT)
    # ... for its stop_time (0.3 s), then nothing: the arbitration yields to other sources
    assert wait_until(lambda: silent_for(h.chassis, 0.5), WAIT)
    # each link on /diagnostics every diagnostics_period (1 s)
    assert wait_until(lambda: (s := h.diagnostic('rm_robot: manual dr16', h.diagnostics))
                      and int(s['frames_ok']) > 0, WAIT)
    assert wait_until(lambda: h.diagnostic('rm_robot: manual image link', h.diagnostics), WAIT)
