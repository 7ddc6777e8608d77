"""rm_plugins/Referee in rm_robot: referee frames on a pty -> rm_msgs reports, link states.

The host runs in-process with the Referee plugin reading a pseudo-terminal; the test
writes the protocol notes' frames (docs/PROTOCOLS.md §6) into it, split and with garbage
between, and watches the plugin's topics only.
"""

import math
import os

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.parameter import Parameter
from rm_base.errors import ConfigError
from rm_base.hardware.protocols import referee as ref
from rm_base.host import RobotHost
from rm_base.plugin import STATE_QOS
from rm_plugins.serial import LinkState
from support.hosted import HostedPlugins
from support.ros import wait_until
from support.serial_port import Pty

from rm_msgs.msg import (
    PluginState,
    RefereeGameStatus,
    RefereeInteraction,
    RefereeKeyboardMouse,
    RefereePowerHeat,
    RefereeRobotStatus,
    RefereeShot,
)

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 10.0  # longest wait for any condition [s]; normally met in well under a second

F1 = bytes.fromhex('A5 0B 00 01 5C 01 00 41 2B 01 00 F1 53 65 00 00 00 00 85 6C')
F2 = bytes.fromhex('A5 0D 00 02 6F 01 02 03 02 B4 00 C8 00 28 00 F0 00 3C 00 07 7A FC')
F4 = bytes.fromhex('A5 10 00 04 E8 02 02 C0 5D C4 09 00 00 70 42 39 00 78 00 00 00 00 00 11 DC')
F5 = bytes.fromhex('A5 0E 00 05 08 02 02 00 00 00 00 00 00 00 00 3C 00 82 00 00 00 14 3F')
F8 = bytes.fromhex('A5 07 00 08 7B 07 02 01 01 0A 00 00 C4 41 0E A5')
F6 = bytes.fromhex('A5 0C 00 06 A5 04 03 64 00 CE FF 00 00 01 00 91 00 00 00 97 DE')
V1 = bytes.fromhex('A9 53 94 06 20 AF D8 A2 60 19 F9 FF 0F 00 00 00 01 20 02 DE 1C')


class Harness(HostedPlugins):
    def __init__(self, context, port, **overrides):
        super().__init__(context, {
            'plugins': ['referee'],
            'referee.type': 'rm_plugins/Referee',
            'referee.rate': 50.0,
            'referee.port': port,
            'referee.protocol_version': 2026,
            'referee.data_timeout': 0.3,
            'referee.diagnostics_period': 0.1,
            **overrides,
        })
        self.received = {
            topic: self.collect(msg_type, f'/referee/{topic}')
            for topic, msg_type in (('game_status', RefereeGameStatus),
                                    ('robot_status', RefereeRobotStatus),
                                    ('power_heat', RefereePowerHeat), ('shot', RefereeShot))
        }
        self.keyboard = self.collect(RefereeKeyboardMouse, '/referee/keyboard_mouse')
        self.diagnostics = self.collect(DiagnosticArray, '/diagnostics')
        self.states = self.collect(PluginState, '/rm_robot/referee/state', STATE_QOS)
        self.start()

    def state(self):
        return LinkState(self.states[-1].state) if self.states else None

    def status(self):
        return self.diagnostic('rm_robot: referee', self.diagnostics)


@pytest.fixture
def rig(ros_context, tmp_path):
    path = str(tmp_path / 'referee')
    pty = Pty(path)
    harness = Harness(ros_context, path)
    yield harness, pty
    harness.close()
    pty.close()


def test_reports_arrive_in_si_and_a_lost_link_is_a_state(rig):
    h, pty = rig
    assert wait_until(lambda: h.state() is LinkState.NO_DATA, WAIT)  # open, nothing yet
    stream = b'\x00\xa5\x13' + F1 + b'\xa5' + F2 + F5 + F8
    for i in range(0, len(stream), 7):  # split reads, garbage between frames
        pty.write(stream[i:i + 7])
    assert wait_until(lambda: all(h.received.values()), WAIT), {
        k: len(v) for k, v in h.received.items()
    }
    game = h.received['game_status'][-1]
    assert (game.progress, game.stage_remaining) == (RefereeGameStatus.PROGRESS_IN_MATCH, 299)
    robot = h.received['robot_status'][-1]
    assert (robot.robot_id, robot.barrel_heat_limit, robot.chassis_power_limit) == (3, 240.0, 60.0)
    assert math.isnan(robot.bullet_speed_limit)  # the 13-byte layout has none
    power = h.received['power_heat'][-1]
    assert (power.buffer_energy, power.heat_17mm) == (60.0, 130.0)
    assert math.isnan(power.chassis_power)  # 2026: not reported
    assert h.received['shot'][-1].speed == pytest.approx(24.5)
    assert robot.header.stamp.sec > 0
    assert wait_until(lambda: h.state() is LinkState.STREAMING, WAIT)
    # silence: no frame for data_timeout (0.3 s) is the lost link
    assert wait_until(lambda: h.state() is LinkState.NO_DATA, WAIT)


def test_a_layout_of_another_season_is_counted_not_published(rig):
    h, pty = rig
    # pyserial flushes the input queue when it opens the port: write once it is open
    assert wait_until(lambda: h.state() is LinkState.NO_DATA, WAIT)
    pty.write(F4 + F1)  # F4: the 16-byte 2024 power/heat, unknown to the 2026 protocol
    assert wait_until(lambda: h.received['game_status'], WAIT)
    assert wait_until(
        lambda: (s := h.status()) is not None and s['wrong_length'] == '0x0202/16 B: 1', WAIT
    ), h.status()
    assert h.received['power_heat'] == []
    assert ref.ProtocolVersion(h.status()['protocol_version']) is ref.ProtocolVersion.V2026


def test_a_protocol_the_plugin_does_not_know_is_refused_naming_the_key(ros_context, tmp_path):
    overrides = {
        'plugins': ['referee'], 'referee.type': 'rm_plugins/Referee',
        'referee.port': str(tmp_path / 'referee'), 'referee.protocol_version': 2023,
    }
    with pytest.raises(ConfigError, match=r'referee\.protocol_version.*>= 2024'):
        RobotHost(
            context=ros_context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )


def test_the_image_links_keyboard_and_mouse_are_published_from_both_frame_kinds(
    ros_context, tmp_path
):
    # the Referee plugin on the image link's port: its 0x0304 and A9 53 frames
    pty = Pty(str(tmp_path / 'image_link'))
    h = Harness(ros_context, pty.path, **{'referee.image_link': True})
    try:
        _keyboard_and_mouse(h, pty)
    finally:
        h.close()
        pty.close()


def _keyboard_and_mouse(h, pty):
    assert wait_until(lambda: h.state() is LinkState.NO_DATA, WAIT)  # open, nothing yet

    def sent(frame):
        # again until the subscription has matched: what came before it is not replayed
        pty.write(frame)
        return h.keyboard and h.keyboard[-1].keys == keys

    keys = 0x0091
    assert wait_until(lambda: sent(F6), WAIT)  # 0x0304: mouse (100, -50, 0), left, W SHIFT E
    k = h.keyboard[-1]
    assert (k.mouse_x, k.mouse_y, k.left, k.right, k.keys) == (100, -50, True, False, 0x0091)
    keys = 0x0220
    assert wait_until(lambda: sent(V1), WAIT)  # A9 53: mouse (-7, 15, 0), left, CTRL + F
    k = h.keyboard[-1]
    assert (k.mouse_x, k.mouse_y, k.left, k.keys) == (-7, 15, True, 0x0220)


def test_interaction_content_goes_out_on_the_port_paced_once_the_robot_id_is_known(rig):
    h, pty = rig
    os.set_blocking(pty.master, False)
    publisher = h.probe.create_publisher(RefereeInteraction, '/referee/interaction', 10)
    assert wait_until(lambda: publisher.get_subscription_count() > 0, WAIT)
    content_id, content = ref.drawing([ref.circle(b'CIR', (960, 540), 30)])
    for _ in range(3):
        publisher.publish(RefereeInteraction(content_id=content_id, content=list(content)))
    pty.write(F2)  # robot status: robot 3
    parser = ref.FrameParser()
    frames = []

    def read():
        try:
            frames.extend(f for f in parser.feed(os.read(pty.master, 4096)) if f.cmd_id == 0x0301)
        except BlockingIOError:
            pass
        return len(frames) >= 3

    assert wait_until(read, WAIT)
    sent = ref.decode_interaction(frames[0].data)
    assert (sent.content_id, sent.sender_id, sent.receiver_id) == (0x0101, 3, 0x0103)
    assert ref.decode_drawing(sent.content_id, sent.content)[0][0].name == b'CIR'
    assert wait_until(lambda: (h.status() or {}).get('0x0301 sent') == '3', WAIT), h.status()
