"""Referee: the referee system's serial link -> typed rm_msgs reports, SI units.

A ``SerialReader`` owns the port (the power-management module's user UART, 115200 baud; a
pyserial URL, ``~`` and ``${VAR}`` expanded) while the plugin is enabled; the control loop
reads it after every tick (outside a loop, the reader's thread does). It splits the
byte stream into frames (resyncing on bad CRCs and split reads), decodes them for the
configured ``protocol_version`` and publishes each report at once on
``referee/game_status``, ``referee/robot_status``, ``referee/power_heat``,
``referee/shot``, ``referee/projectiles``, ``referee/hurt`` and ``referee/keyboard_mouse``
(rm_msgs Referee*; the image link's 0x0304 or ``A9 53`` frames: run a second instance on
that port, 921600 baud, ``image_link: true``, to hear the operator's keyboard and mouse). The
robot's other plugins get them in-process with no DDS hop (the outbox's loopback). A frame
whose length fits no layout of the version, or a command this plugin does not read, is
counted on /diagnostics and dropped.

States are a serial device's (``LinkState``): NO_DATA is the lost link, no good frame
for ``data_timeout`` (the referee sends robot status and power/heat at 10 Hz). Consumers
of the limits fall back to their own conservative configuration then, never to none.
docs/PROTOCOLS.md §6.
"""

from __future__ import annotations

import dataclasses
import threading
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.time import Time
from rm_base.errors import InputRejectedError
from rm_base.hardware.protocols.referee import (
    FrameParser,
    ProtocolVersion,
    RawFrame,
    RobotStatus,
    StatusDecoder,
)
from rm_base.plugin import LogThrottle, PluginBase

from rm_msgs.msg import RefereeInteraction
from rm_plugins.referee.interaction import InteractionLink
from rm_plugins.referee.messages import TOPICS
from rm_plugins.referee.power_watch import PowerWatch
from rm_plugins.serial.device import DeviceLink, LinkState, link_status, read_serial_settings

_NS_PER_S = 1_000_000_000
_QOS_DEPTH = 10


class Referee(PluginBase):
    """The referee system's serial link, published as rm_msgs Referee* reports.

    Parameters (under ``<name>.``): ``port`` (required), ``baudrate`` (115200),
    ``image_link`` (the port is the image link's: also its ``A9 53`` frames; false),
    ``protocol_version`` (``2024``, ``2025``, ``2026``), ``data_timeout`` (no good frame this
    long: the link is lost, 0.5 s), the reader's ``read_timeout``, ``reopen_backoff_min`` /
    ``_max``, ``silence_reopen`` and ``diagnostics_period``.
    """

    State = LinkState

    def on_init(self) -> None:
        """Read the parameters, create the publishers and the (not yet started) reader."""
        p = self.params
        self._settings = settings = read_serial_settings(
            p, baudrate=115200, data_timeout=0.5, silence_reopen=2.0
        )
        version = ProtocolVersion(str(p.integer(
            'protocol_version', 2026, ge=2024, le=2026,
            description="the season's referee protocol (its frames' layouts): 2024, 2025, 2026",
        )))
        by_topic: dict[str, Any] = {}
        self._publishers = {}
        for record, (topic, msg_type, convert) in TOPICS.items():
            if topic not in by_topic:
                by_topic[topic] = self.create_publisher(msg_type, topic, _QOS_DEPTH)
            self._publishers[record] = (by_topic[topic], convert)
        self._diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._decoder = StatusDecoder(version)
        self._clock = self.node.get_clock()
        self._lock = threading.Lock()
        self._published = 0
        self._next_diagnostics_ns: int | None = None
        self._report_bad = 0
        self._power_watch = PowerWatch()
        image_link = p.boolean(
            'image_link', False,
            description="the port is the image link's: also read its A9 53 remote frames",
        )
        self._link = DeviceLink(
            self, settings, self._on_frame, parser=FrameParser(image_link=image_link),
            name='referee',
        )
        self.reader = self._link.reader
        # what the robot sends: 0x0301 content from referee/interaction (the client UI)
        self._interaction = InteractionLink(
            p.double('interaction.bandwidth', 3720.0, unit='B/s', gt=0.0,
                     description='most bytes a second of 0x0301 frames (the rules: 3720)'),
            p.double('interaction.max_hz', 10.0, unit='Hz', gt=0.0, le=30.0,
                     description='most 0x0301 frames a second (the rules: 30; 10 in older '
                     'tables)'),
        )
        self._robot_id: int | None = None
        self._write_failures = 0
        self._refusals = LogThrottle(5 * _NS_PER_S)
        self.subscribe('referee/interaction', RefereeInteraction, self._on_interaction, 10)

    def on_enable(self) -> None:
        """Start the reader (its thread opens the port)."""
        self._link.start()

    def on_disable(self) -> None:
        """Stop the reader and close the port."""
        self._link.stop()

    def update(self, now: Time, dt: float) -> None:
        """Decide the link state; send a 0x0301 frame when due; /diagnostics when due."""
        now_ns = now.nanoseconds
        state, reason, stats = self._link.decide(now_ns)
        self.transition(state, reason)
        with self._lock:
            frame = self._interaction.take(self._robot_id, now_ns)
        if frame is not None and not self.reader.write(frame):
            self._write_failures += 1
        if self._next_diagnostics_ns is None or now_ns >= self._next_diagnostics_ns:
            self._next_diagnostics_ns = now_ns + round(
                self._settings.diagnostics_period * _NS_PER_S
            )
            self._publish_diagnostics(now, stats)

    def _on_frame(self, frame: RawFrame) -> None:
        """Decode and publish one frame (called in the reading thread)."""
        now = self._clock.now()
        with self._lock:  # the decoder's counters are read by the diagnostics (tick)
            record = self._decoder.decode(frame)
        self._link.received(now.nanoseconds)
        if isinstance(record, RobotStatus):
            self._robot_id = record.robot_id
            said = self._power_watch.note(record)
            if said is not None:
                self.logger.warning(said)
        entry = self._publishers.get(type(record))
        if entry is None:
            return  # counted by the decoder (ignored, wrong length or rejected)
        publisher, convert = entry
        msg = convert(record)
        msg.header.stamp = now.to_msg()
        publisher.publish(msg)
        with self._lock:
            self._published += 1

    def _on_interaction(self, msg: RefereeInteraction, receive_ns: int) -> None:
        """Queue 0x0301 content to send (the subscription's thread)."""
        try:
            with self._lock:
                self._interaction.offer(msg.content_id, msg.receiver_id, bytes(msg.content))
        except InputRejectedError as err:
            tail = self._refusals.due(receive_ns)
            if tail is not None:
                self.logger.warning(f'referee/interaction refused: {err}{tail}')

    def _publish_diagnostics(self, now: Time, stats: Any) -> None:
        decoder = self._decoder
        with self._lock:
            published = self._published
            wrong, ignored, rejected = (
                dict(decoder.wrong_length), dict(decoder.ignored), dict(decoder.rejected)
            )
        bad = stats.bad_frames + sum(wrong.values()) + sum(rejected.values())
        new_bad, self._report_bad = bad - self._report_bad, bad
        status = link_status(
            f'{self.node.get_name()}: {self.name}', self._settings,
            LinkState(self.state.value), stats, reason=self.reason, new_bad=new_bad,
            values={
                'protocol_version': decoder.version.value,
                'published': published,
                'wrong_length': _counts(wrong),
                'ignored': _counts(ignored),
                'rejected': _counts(rejected),
                **self._interaction_values(),
            },
        )
        msg = DiagnosticArray()
        msg.header.stamp = now.to_msg()
        msg.status = [status]
        self._diagnostics.publish(msg)


    def _interaction_values(self) -> dict[str, Any]:
        with self._lock:
            sent = dataclasses.replace(self._interaction.stats)
        return {
            '0x0301 sent': sent.sent, '0x0301 bytes': sent.bytes_sent,
            '0x0301 dropped (queue full)': sent.dropped, '0x0301 refused': sent.refused,
            '0x0301 write failures': self._write_failures,
        }


def _counts(counter: Any) -> str:
    return ', '.join(f'{_key(k)}: {n}' for k, n in sorted(counter.items())) or 'none'


def _key(key: Any) -> str:
    if isinstance(key, tuple):
        return f'0x{key[0]:04X}/{key[1]} B'
    return f'0x{key:04X}'
