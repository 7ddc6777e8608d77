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

A **stepped** peer has no threads: the world's stepper calls :meth:`BusPeer.settle` after
each half of a tick (the world's step, the robot's tick), which moves what the robot sent
into the channels and returns only when every frame either side has sent so far has
reached every reader (on a kernel interface, proven by a :class:`FrameWitness`). A frame
that does not arrive within :data:`SETTLE_S` is an error, never a silent loss.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Mapping, Sequence

import can

from rm_base.sim.channel import SimChannel
from rm_base.sim.frame_witness import FrameWitness
from rm_base.sim.world import SimWorld
from rm_base.sim_devices.errors import SimStateError

_log = logging.getLogger(__name__)

#: How long a reader waits for a frame before it checks for stop() [s].
RECEIVE_S = 0.1
#: How long a reader waits after a failed read before it tries again [s].
RETRY_S = 0.1
#: How long settle() waits for frames already sent (real time; the guest kernel is slow) [s].
SETTLE_S = 10.0


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
        stepped: no reader threads; the stepper calls :meth:`settle`.
        witnesses: world channel name -> the kernel interface a :class:`FrameWitness`
            watches (stepped, on socketcan: every channel); the peer closes them.

    Raises:
        SimLookupError: a channel the world does not have.
    """

    def __init__(
        self,
        world: SimWorld,
        buses: Mapping[str, can.BusABC],
        *,
        stepped: bool = False,
        witnesses: Mapping[str, FrameWitness] | None = None,
    ) -> None:
        self.world = world
        self.stepped = stepped
        self.endpoints = {name: _BusEndpoint(bus, world.channel(name))
                          for name, bus in buses.items()}
        self.witnesses = dict(witnesses or {})
        self._stop = threading.Event()
        self._threads = [] if stepped else [
            threading.Thread(target=self._read, args=(endpoint,), daemon=True,
                             name=f'rm_sim-{name}')
            for name, endpoint in self.endpoints.items()
        ]

    @classmethod
    def open(cls, world: SimWorld, interface: str, *, stepped: bool = False) -> BusPeer:
        """The world's every channel on the python-can bus of interface named as it.

        Stepped on socketcan, each channel also gets its :class:`FrameWitness`.

        Raises:
            can.CanInitializationError: a bus cannot be opened (socketcan: no such
                interface, OSError 19), naming it.
        """
        buses: dict[str, can.BusABC] = {}
        witnesses: dict[str, FrameWitness] = {}
        try:
            for name in sorted(world.channels):
                buses[name] = can.Bus(interface=interface, channel=name)
                if stepped and interface == 'socketcan':
                    witnesses[name] = FrameWitness(name)
        except (can.CanError, OSError) as err:
            for bus in buses.values():
                bus.shutdown()
            for witness in witnesses.values():
                witness.close()
            raise can.CanInitializationError(
                f'rm_sim cannot open {interface} channel {name}: {err}'
            ) from err
        return cls(world, buses, stepped=stepped, witnesses=witnesses)

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
        for witness in self.witnesses.values():
            witness.close()

    def settle(self, robot_sent: Mapping[str, int], timeout_s: float = SETTLE_S) -> None:
        """Stepped: hand the robot's frames to the channels and wait until nothing is in flight.

        Args:
            robot_sent: world channel name -> frames the robot's bus on it has sent so far.
            timeout_s: how long to wait for frames already sent [s].

        Raises:
            SimStateError: a frame already sent has not arrived within timeout_s.
        """
        for name, endpoint in self.endpoints.items():
            sent = robot_sent.get(name, 0)
            deadline = time.monotonic() + timeout_s
            while True:
                waiting = endpoint.received < sent
                left = deadline - time.monotonic()
                if waiting and left <= 0.0:
                    raise SimStateError(
                        f"rm_sim on {name}: {sent - endpoint.received} of the robot's frames "
                        f'did not arrive within {timeout_s:g} s'
                    )
                taken = self._take(endpoint, min(left, RECEIVE_S) if waiting else 0.0)
                if taken is None or (not taken and not waiting):
                    break  # the link is down (the robot's sends fail too), or all is in
            witness = self.witnesses.get(name)
            total = endpoint.sent + sent
            if witness is not None and not witness.wait_for(total, timeout_s):
                raise SimStateError(
                    f'{witness.interface}: {total - witness.count} frames sent are not yet '
                    f'on every socket after {timeout_s:g} s'
                )

    def _take(self, endpoint: _BusEndpoint, timeout_s: float) -> bool | None:
        """Read one frame (waiting up to timeout_s) into the channel.

        Returns:
            True: a frame; False: none came; None: the bus cannot be read (link down).
        """
        try:
            msg = endpoint.bus.recv(timeout_s)
        except can.CanError:
            endpoint.read_errors += 1
            return None
        if msg is None:
            return False
        if not msg.is_error_frame:
            self._hand_over(endpoint, msg)
        return True

    @staticmethod
    def _hand_over(endpoint: _BusEndpoint, msg: can.Message) -> None:
        endpoint.received += 1
        try:
            endpoint.channel.send(endpoint, msg, None)
        except can.CanOperationError:
            pass  # an injected bus-off: the channel counts the frame as lost

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
            self._hand_over(endpoint, msg)
