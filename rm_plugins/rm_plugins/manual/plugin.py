"""ManualControl: the operator's DR16 remote and keyboard/mouse -> the robot's command topics.

It publishes the messages any user publishes (``chassis_cmd`` + ``vel_cmd``,
``gimbal_cmd``, ``shoot_cmd``), under its own namespace (``namespace``, default
``/manual``: ``/manual/chassis_cmd``...), where rm_robot's command arbitration takes them
as the ``manual`` source, above ``topic pub`` and planners (docs/ARCHITECTURE.md,
"Command arbitration"); at its own rate, from the DR16 receiver (``dr16.port``,
100000 baud 8E1 behind the receiver's inverter) and, optionally, the keyboard and mouse the
image link forwards (``image_link.port``: 0x0304 frames up to 2026 V1.1, the 2025+ ``A9 53``
remote frame). What each switch, stick, key and mouse button does is the mapping file's
(``mapping_file``; the default is ``rm_plugins/manual/default_mapping.yaml``).

States are the DR16 link's (``LinkState``); each link is reported on /diagnostics at its
``diagnostics_period``. The remote is heard only once it behaves like a DR16
(:class:`~rm_base.hardware.protocols.dbus.DbusTrust`: three frames in the 14 ms rhythm
without a jump of every channel); noise on a silent port is counted and never commands.
Until the remote is heard it publishes nothing, so a robot driven by other nodes (or
`ros2 topic pub`) is not disturbed by a receiver nobody transmits to. Once heard, it
streams the operator's commands; without a good DR16 frame for ``dr16.data_timeout``
(100 ms) it publishes PASSIVE for ``stop_time`` (0.3 s), so every mechanism stops at once,
and then falls silent (the keyboard's toggles reset) until the remote is heard again:
the arbitration then yields to the next source. The operator's own PASSIVE (right switch
down) is streamed like any command, and wins over every lower source. Disabling the
plugin silences it. The image link is optional: lost, it just adds nothing.
"""

from __future__ import annotations

import threading

import serial
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from rclpy.time import Time
from rm_base.hardware.protocols import dbus
from rm_base.hardware.protocols import referee as ref
from rm_base.plugin import PluginBase

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd
from rm_plugins.manual.driver import (
    Commands,
    Keyboard,
    ManualDriver,
    OperatorInput,
    command_messages,
)
from rm_plugins.manual.mapping import load_mapping
from rm_plugins.serial.device import DeviceLink, LinkState, link_status, read_serial_settings
from rm_plugins.serial.reader import ReaderStats

_NS_PER_S = 1_000_000_000
_QOS_DEPTH = 10


class ManualControl(PluginBase):
    """Manual control from the DR16 and the image link (see the module docstring).

    Parameters (under ``<name>.``): ``mapping_file`` ('' = the default mapping),
    ``dr16.port`` (required) and the reader's ``dr16.*`` (``data_timeout`` 0.1 s...),
    ``image_link.port`` ('' = none), ``image_link.baudrate`` (921600; 115200 for 0x0304 on
    the older links), ``image_link.data_timeout`` (0.2 s).
    """

    State = LinkState

    def on_init(self) -> None:
        """Read the mapping and the ports; create the publishers and the readers."""
        # A receiver whose remote is off is silent, as is a link with no client: silence
        # is no reason to reopen either port (silence_reopen 0).
        p = self.params
        self._driver = ManualDriver(load_mapping(p.string(
            'mapping_file', '',
            description="YAML mapping of switches, sticks, keys and mouse; '' = the default",
        )))
        dr16 = read_serial_settings(
            p.group('dr16'), baudrate=dbus.BAUD_RATE, data_timeout=0.1, silence_reopen=0.0
        )
        self._dr16 = DeviceLink(
            self, dr16, self._on_dbus, parser=dbus.DbusStream(), name='dr16', polled=False,
            parity=serial.PARITY_EVEN,
        )
        self.reader = self._dr16.reader
        link_port = p.string(
            'image_link.port', '',
            description="the image link's serial port (keyboard and mouse); '' = none",
        )
        self._image_link: DeviceLink | None = None
        if link_port:
            settings = read_serial_settings(
                p.group('image_link'), baudrate=921600, data_timeout=0.2, silence_reopen=0.0,
                port=link_port,
            )
            self._image_link = DeviceLink(
                self, settings, self._on_image_link, parser=ref.FrameParser(image_link=True),
                name='image link',
            )
        self._keyboard_decoder = ref.StatusDecoder(ref.ProtocolVersion.V2025)
        namespace = p.string(
            'namespace', '/manual',
            description='namespace of the command topics it publishes (the manual command '
                        "source of rm_robot's arbitration); '' publishes the plain topics",
        ).rstrip('/')
        self._stop_ns = round(p.double(
            'stop_time', 0.3, unit='s', ge=0.0, le=5.0,
            description='after the remote is lost, publish PASSIVE this long, then nothing',
        ) * _NS_PER_S)
        self._trust = dbus.DbusTrust(dr16.data_timeout)
        self._lost_ns: int | None = None  # when the link was found lost, while stopping
        self._publishers = {
            topic: self.create_publisher(msg_type, f'{namespace}/{topic}', _QOS_DEPTH,
                                         hand_over=True)
            for topic, msg_type in (('chassis_cmd', ChassisCmd), ('vel_cmd', Twist),
                                    ('gimbal_cmd', GimbalCmd), ('shoot_cmd', ShootCmd))
        }
        self._diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._next_diagnostics_ns: dict[str, int] = {}
        self._reported_bad: dict[str, int] = {}
        self._lock = threading.Lock()
        self._remote: dbus.DbusFrame | None = None  # None: not heard since enabled
        self._keyboard: tuple[Keyboard, int] | None = None  # and its receive time [ns]

    def on_enable(self) -> None:
        """Start the readers (they open the ports)."""
        self._dr16.start()
        if self._image_link is not None:
            self._image_link.start()

    def on_disable(self) -> None:
        """Stop the readers; forget what the operator held."""
        self._dr16.stop()
        if self._image_link is not None:
            self._image_link.stop()
        with self._lock:
            self._remote = self._keyboard = None
            self._trust = dbus.DbusTrust(self._dr16.settings.data_timeout)
        self._lost_ns = None

    # -- input (reader threads, or a harness stepping the robot) ------------------------------

    def on_remote_frame(self, frame: dbus.DbusFrame, receive_ns: int) -> None:
        """A DR16 frame arrived at receive_ns (node clock); believed as DbusTrust says."""
        with self._lock:
            believed = self._trust.accept(frame, receive_ns)
            if believed:
                self._remote = frame
        if believed:
            self._dr16.received(receive_ns)

    def on_keyboard(self, keyboard: Keyboard, receive_ns: int) -> None:
        """The image link's keyboard and mouse arrived at receive_ns (node clock)."""
        with self._lock:
            self._keyboard = (keyboard, receive_ns)
        if self._image_link is not None:
            self._image_link.received(receive_ns)

    def _on_dbus(self, frame: dbus.DbusFrame) -> None:
        self.on_remote_frame(frame, self.node.get_clock().now().nanoseconds)

    def _on_image_link(self, raw: ref.RawFrame) -> None:
        record = self._keyboard_decoder.decode(raw)
        now_ns = self.node.get_clock().now().nanoseconds
        if isinstance(record, ref.KeyboardMouse):
            self.on_keyboard(Keyboard(record.mouse_x, record.mouse_y, record.left, record.right,
                                      record.keys), now_ns)
        elif isinstance(record, ref.RemoteFrame):
            self.on_keyboard(Keyboard(record.mouse_x, record.mouse_y, record.mouse_left,
                                      record.mouse_right, record.keys), now_ns)

    # -- the tick ------------------------------------------------------------------------------

    def update(self, now: Time, dt: float) -> None:
        """Decide the DR16 link, turn the operator's input into commands, publish them."""
        now_ns = now.nanoseconds
        state, reason, stats = self._dr16.decide(now_ns)
        self.transition(state, reason)
        self._publish_diagnostics(now, state, reason, stats)
        with self._lock:
            remote, keyboard = self._remote, self._keyboard
        if remote is None:
            return  # not heard: someone else may be driving
        if state is not LinkState.STREAMING:
            if self._lost_ns is None:
                self._lost_ns = now_ns
                self.logger.warning(
                    f'remote lost: PASSIVE for {self._stop_ns / _NS_PER_S:g} s, then silent')
            if now_ns - self._lost_ns <= self._stop_ns:
                self._publish(self._driver.lost(), now)
                return
            with self._lock:  # stopped: yield until the remote is heard again
                if self._remote is remote:
                    self._remote = None
            self._lost_ns = None
            return
        self._lost_ns = None
        operator = OperatorInput.from_dbus(remote, self._driver.mapping)
        timeout_ns = self._image_link.settings.data_timeout * _NS_PER_S if self._image_link else 0
        if keyboard is not None and now_ns - keyboard[1] <= timeout_ns:
            operator = operator.plus_keyboard(keyboard[0])
        self._publish(self._driver.commands(operator), now)

    def _publish_diagnostics(
        self, now: Time, state: LinkState, reason: str, stats: ReaderStats
    ) -> None:
        """A status per link when its diagnostics_period is due: the DR16's, the image link's."""
        now_ns = now.nanoseconds
        links = [('dr16', self._dr16, state, reason, stats)]
        if self._image_link is not None:
            link_state, link_reason, link_stats = self._image_link.decide(now_ns)
            links.append(('image link', self._image_link, link_state, link_reason, link_stats))
        msg = DiagnosticArray()
        msg.header.stamp = now.to_msg()
        for label, link, link_state, link_reason, link_stats in links:
            if now_ns < self._next_diagnostics_ns.get(label, now_ns):
                continue
            period_ns = round(link.settings.diagnostics_period * _NS_PER_S)
            self._next_diagnostics_ns[label] = now_ns + period_ns
            bad = link_stats.bad_frames
            new_bad = bad - self._reported_bad.get(label, 0)
            self._reported_bad[label] = bad
            values = {'noise_frames': self._trust.noise_frames} if link is self._dr16 else {}
            msg.status.append(link_status(
                f'{self.node.get_name()}: {self.name} {label}', link.settings, link_state,
                link_stats, reason=link_reason, new_bad=new_bad, values=values,
            ))
        if msg.status:
            self._diagnostics.publish(msg)

    def _publish(self, c: Commands, now: Time) -> None:
        for topic, msg in command_messages(c, now.to_msg()).items():
            self._publishers[topic].publish(msg)
