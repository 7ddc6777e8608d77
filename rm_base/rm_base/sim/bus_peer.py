"""A simulated world's channels on python-can buses: rm_sim as the motors on a kernel bus.

Each world channel is joined to one python-can bus (on Linux a socketcan channel such as
vcan0, where the robot's own socketcan bus sits too): a frame read from the bus goes on the
channel as the robot's, and every frame the channel's motors send goes out on the bus. The
robot then runs on ``interface: socketcan`` unchanged; only its channel names say vcan.

Threads: one reader per bus; the world's physics thread sends (under the world's lock, so
never blocking: a frame the kernel will not take at once is dropped and counted, as a full
transmit queue drops it on a robot). A bus whose link is down (``ip link set vcan0 down``:
python-can raises CanOperationError, errno 100) is read again every :data:`RETRY_S` until
it is up, each outage logged once.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping, Sequence

import can

from rm_base.sim.channel import SimChannel
from rm_base.sim.world import SimWorld

_log = logging.getLogger(__name__)

#: How long a reader waits for a frame before it checks for stop() [s].
RECEIVE_S = 0.1
#: How long a reader waits after a failed read before it tries again [s].
RETRY_S = 0.1


class _BusEndpoint:
    """One bus as an endpoint of its channel: what the motors send goes out on it."""

    receive_own_messages = False

    def __init__(self, bus: can.BusABC, channel: SimChannel) -> None:
        self.bus = bus
        self.channel = channel
        self.sent = self.dropped = self.received = self.read_errors = 0

    def _deliver(self, msg: can.Message) -> None:
        self._deliver_all((msg,))

    def _deliver_all(self, msgs: Sequence[can.Message]) -> None:
        # The physics thread, under the world's lock: never block here.
        for msg in msgs:
            try:
                self.bus.send(msg, timeout=0.0)
                self.sent += 1
            except can.CanError:
                self.dropped += 1


class BusPeer:
    """The world's channels on buses (see the module docstring).

    Args:
        world: the simulated world.
        buses: world channel name -> the bus it is joined to (the peer closes them).

    Raises:
        SimLookupError: a channel the world does not have.
    """

    def __init__(self, world: SimWorld, buses: Mapping[str, can.BusABC]) -> None:
        self.world = world
        self.endpoints = {name: _BusEndpoint(bus, world.channel(name))
                          for name, bus in buses.items()}
        self._stop = threading.Event()
        self._threads = [
            threading.Thread(target=self._read, args=(endpoint,), daemon=True,
                             name=f'rm_sim-{name}')
            for name, endpoint in self.endpoints.items()
        ]

    def start(self) -> None:
        """Join every channel to its bus and start reading."""
        for endpoint in self.endpoints.values():
            endpoint.channel.attach(endpoint)
        for thread in self._threads:
            thread.start()

    def stop(self) -> None:
        """Stop reading, leave the channels, close the buses (idempotent)."""
        self._stop.set()
        for thread in self._threads:
            if thread.is_alive():
                thread.join(timeout=5.0)
        for endpoint in self.endpoints.values():
            endpoint.channel.detach(endpoint)
            endpoint.bus.shutdown()

    def _read(self, endpoint: _BusEndpoint) -> None:
        down = False
        while not self._stop.is_set():
            try:
                msg = endpoint.bus.recv(RECEIVE_S)
            except can.CanError as err:
                endpoint.read_errors += 1
                if not down:
                    _log.warning('rm_sim: %s cannot be read: %s', endpoint.channel.name, err)
                down = True
                self._stop.wait(RETRY_S)
                continue
            if down:
                _log.info('rm_sim: %s is read again', endpoint.channel.name)
                down = False
            if msg is None or msg.is_error_frame:
                continue
            endpoint.received += 1
            try:
                endpoint.channel.send(endpoint, msg, None)
            except can.CanOperationError:
                pass  # an injected bus-off: the channel counts the frame as lost
