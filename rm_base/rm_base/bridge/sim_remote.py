"""The simulated DR16 receiver's transmitter: ``<prefix>remote`` (rm_msgs/RemoteInput).

Each message is what the operator holds now; the simulated receiver sends it to the robot
every 14 ms, as the DR16 does, from the first message on. When messages stop for
:data:`TRANSMITTER_LOST_S` (the operator's program ended or hung) the receiver goes silent,
as a DR16 does when its transmitter is switched off, and the robot's manual control sees
the remote lost. A message the frame cannot carry (a switch of 0, a stick beyond ±660) is
refused, counted and logged at most once a second; the receiver keeps what it sent.
Served by the rm_sim process (prefix ``~/``) and by can_bridge running rm_sim in-process
(``~/sim/``) when the world has a remote (``sim.remote``).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

from rclpy.qos import QoSProfile, ReliabilityPolicy

from rm_base.hardware.protocols.dbus import DbusFrame, Switch
from rm_base.sim import SimWorld
from rm_base.sim_devices.errors import SimConfigError
from rm_msgs.msg import RemoteInput

#: No message this long [s]: the transmitter is off and the receiver silent.
TRANSMITTER_LOST_S = 0.5
#: At most one log line per this period [s] about refused messages.
_REJECT_LOG_PERIOD = 1.0
# Operator input goes out at tens of Hz; a late one is useless, a lost one is replaced.
_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


def frame_of(msg: RemoteInput) -> DbusFrame:
    """The DBUS frame a message describes. Raises: ValueError: a switch is not 1, 2 or 3."""
    c0, c1, c2, c3 = (int(c) for c in msg.channels)
    return DbusFrame(
        (c0, c1, c2, c3), Switch(msg.switch_a), Switch(msg.switch_b),
        (msg.mouse_x, msg.mouse_y, msg.mouse_z), bool(msg.mouse_left), bool(msg.mouse_right),
        msg.keys, msg.wheel,
    )


class SimRemoteInput:
    """The subscription and the transmitter-lost check (see the module docstring).

    Attributes:
        accepted, rejected: messages taken and refused.
        on: the receiver sends (a message came within TRANSMITTER_LOST_S).
    """

    def __init__(self, node: Any, world: SimWorld, *, prefix: str) -> None:
        if world.remote is None:
            raise SimConfigError('the simulated world has no remote (sim.remote)')
        self._node = node
        self._remote = world.remote
        self._lock = world.lock
        self._last = 0.0  # monotonic time of the last accepted message
        self.accepted = self.rejected = 0
        self.on = False
        self.subscription = node.create_subscription(
            RemoteInput, f'{prefix}remote', self._on_input, _QOS
        )
        self._timer = node.create_timer(TRANSMITTER_LOST_S / 5, self._check_lost)

    def _on_input(self, msg: RemoteInput) -> None:
        try:
            frame = frame_of(msg)
            with self._lock:
                self._remote.hold(**{f.name: getattr(frame, f.name)
                                     for f in dataclasses.fields(frame)})
                self._remote.switch_on()
        except (ValueError, SimConfigError) as err:
            self.rejected += 1
            self._node.get_logger().warning(
                f'remote input refused ({self.rejected} so far): {err}',
                throttle_duration_sec=_REJECT_LOG_PERIOD,
            )
            return
        if not self.on:
            self._node.get_logger().info('remote: transmitter on')
        self.accepted += 1
        self.on = True
        self._last = time.monotonic()

    def _check_lost(self) -> None:
        if self.on and time.monotonic() - self._last > TRANSMITTER_LOST_S:
            with self._lock:
                self._remote.switch_off()
            self.on = False
            self._node.get_logger().info('remote: transmitter off (no input for '
                                         f'{TRANSMITTER_LOST_S:g} s)')
