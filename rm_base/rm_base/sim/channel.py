"""Simulated CAN channels: one bus each, its motors, and the python-can buses attached.

Channels are registered by name in a process-wide registry, like python-can's virtual
interface: every :class:`~rm_base.sim.bus.SimBus` opened on a channel name attaches to the
same :class:`SimChannel`, sees every frame the other buses send, and every frame the
channel's motors send. A channel belongs to exactly one
:class:`~rm_base.sim.world.SimWorld`, which creates it (:func:`register_channel`) and
releases it when closed (:func:`release_channel`).
"""

from __future__ import annotations

import collections
import contextlib
import copy
import threading
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import can

from rm_base.sim_devices.device import Frame, SimDevice
from rm_base.sim_devices.errors import SimConfigError, SimStateError

if TYPE_CHECKING:
    from rm_base.sim.world import SimWorld

class _Endpoint(Protocol):
    """What a channel needs from an attached bus (implemented by SimBus).

    An endpoint may also have ``_deliver_all(msgs)``, taking a tick's frames at once.
    """

    receive_own_messages: bool

    def _deliver(self, msg: can.Message) -> None: ...


class CanNode(Protocol):
    """A simulated device on a channel that is not a motor (the super-capacitor board)."""

    @property
    def listen_ids(self) -> frozenset[int]:
        """Standard ids of the frames it reads."""
        ...

    def receive(self, arbitration_id: int, data: bytes, now_ns: int, *,
                is_extended_id: bool = False, is_remote_frame: bool = False,
                is_fd: bool = False) -> list[Frame]:
        """A frame seen on the bus; the frames it answers with."""
        ...

    def emit(self, now_ns: int) -> list[Frame]:
        """The frames it sends on its own at this tick."""
        ...


@dataclass
class ChannelStats:
    """Frame counters of one channel (monotonic).

    Attributes:
        sent: frames sent by buses.
        unclaimed: sent frames no simulated motor listens to (normal for bus-to-bus traffic).
        device_frames: frames sent by the motors (feedback, replies, garbage).
        lost: frames lost to an injected bus-off.
    """

    sent: int = 0
    unclaimed: int = 0
    device_frames: int = 0
    lost: int = 0


_registry: dict[str, SimChannel] = {}
_registry_lock = threading.Lock()


def find_channel(name: str) -> SimChannel | None:
    """Return the registered channel of that name, or None."""
    with _registry_lock:
        return _registry.get(name)


def channel_names() -> list[str]:
    """Names of all registered channels, sorted."""
    with _registry_lock:
        return sorted(_registry)


def register_channel(world: SimWorld, name: str) -> SimChannel:
    """Create world's channel of that name in the registry.

    Raises:
        SimConfigError: another world has a channel of that name.
    """
    with _registry_lock:
        if name in _registry:
            raise SimConfigError(f'channel {name!r} already belongs to another simulated world')
        channel = _registry[name] = SimChannel(world, name)
        return channel


def release_channel(channel: SimChannel) -> None:
    """Close channel and free its name (the world closing)."""
    with _registry_lock:
        channel.closed = True
        if _registry.get(channel.name) is channel:
            del _registry[channel.name]


class SimChannel:
    """One simulated CAN bus: its motors and the python-can buses attached to it.

    Attributes:
        name: channel name (``'can0'``).
        world: the world it belongs to.
        devices: the motors on it, in config order.
        nodes: its other devices (a super-capacitor board), after the motors.
        stats: frame counters.
    """

    def __init__(self, world: SimWorld, name: str):
        self.name = name
        self.world = world
        self.devices: list[SimDevice] = []
        self.nodes: list[CanNode] = []
        self.stats = ChannelStats()
        self._endpoints: list[_Endpoint] = []
        self._state = can.BusState.ACTIVE
        self.closed = False
        # can id -> the devices listening on it, in device order; built for _routed_count
        # devices and nodes (the lists only grow, through SimWorld.add_motor / set_supercap)
        self._routes: dict[int, tuple[SimDevice | CanNode, ...]] = {}
        self._routed_count = 0
        # frames sent while the physics thread held the lock (see send)
        self._handed_over: collections.deque[tuple[_Endpoint | None, can.Message, float | None]] = (
            collections.deque()
        )

    # -- bus faults ----------------------------------------------------------------------

    @property
    def state(self) -> can.BusState:
        """ACTIVE, or the injected PASSIVE / ERROR state."""
        return self._state

    def set_state(self, state: can.BusState) -> None:
        """Inject a bus state.

        ERROR is bus-off: ``send`` raises ``can.CanOperationError`` and no frame moves in
        either direction (the motors' feedback is lost too). PASSIVE (error-passive) only
        changes what ``bus.state`` reports. ACTIVE clears the fault.
        """
        with self.world.lock:
            self._state = can.BusState(state)

    # -- attach ----------------------------------------------------------------------------

    def attach(self, endpoint: _Endpoint) -> None:
        """Connect a bus; it receives every frame from now on."""
        with self.world.lock:
            if self.closed:
                raise SimStateError(f'channel {self.name} is closed')
            self._endpoints.append(endpoint)
            self.world._bus_attached()

    def detach(self, endpoint: _Endpoint) -> None:
        """Disconnect a bus (no-op if it is not attached)."""
        with self.world.lock:
            if endpoint not in self._endpoints:
                return
            self._endpoints.remove(endpoint)
        # Outside the lock: this may close the world, which joins the physics thread.
        self.world._bus_detached()

    @property
    def bus_count(self) -> int:
        """Number of attached buses."""
        return len(self._endpoints)

    # -- traffic ---------------------------------------------------------------------------

    def send(self, sender: _Endpoint | None, msg: can.Message, timestamp: float | None) -> None:
        """Put a frame on the bus: to every other bus, the motors, and the motors' replies.

        Args:
            sender: the sending bus (it gets the frame back only with
                ``receive_own_messages``), or None for a frame from outside any bus.
            msg: the frame.
            timestamp: timestamp for the copies [s]; None uses the world's clock when
                the frame is sent (also for one handed over to a running tick).

        Raises:
            can.CanOperationError: the channel is closed or in (injected) bus-off.
        """
        lock = self.world.lock
        direct: can.Message | None = msg  # None: handed over, the flush sends it
        if not lock.acquire(blocking=False):
            if not self._can_hand_over():
                lock.acquire()
            else:
                # Waiting for the physics tick's lock would cost the sender the GIL; hand
                # the frame (a copy) to the tick, which sends it before it lets go. Stamped
                # now: a tick that lost the CPU must not move the frame later on the wire.
                stamp = self.world.timestamp() if timestamp is None else timestamp
                self._handed_over.append((sender, copy.copy(msg), stamp))
                if not lock.acquire(blocking=False):
                    return
                direct = None  # the tick ended meanwhile: the flush below sends it, in order
        try:
            self.flush_handed_over()
            if direct is not None:
                self._send_locked(sender, direct, timestamp)
        finally:
            lock.release()

    def _can_hand_over(self) -> bool:
        # only to a running physics thread (it flushes every tick), and never a frame that
        # must raise now (closed, bus-off)
        return self.world.running and not self.closed and self._state is not can.BusState.ERROR

    def flush_handed_over(self) -> None:
        """Put the frames handed over during a physics tick on the bus (lock held)."""
        queue = self._handed_over
        while queue:
            sender, msg, timestamp = queue.popleft()
            with contextlib.suppress(can.CanOperationError):  # bus-off since: lost, counted
                self._send_locked(sender, msg, timestamp)

    def _send_locked(
        self, sender: _Endpoint | None, msg: can.Message, timestamp: float | None
    ) -> None:
        if self.closed:
            raise can.CanOperationError(f'rm_sim channel {self.name} is closed')
        if self._state is can.BusState.ERROR:
            self.stats.lost += 1
            raise can.CanOperationError(f'rm_sim channel {self.name} is bus-off (injected)')
        self.stats.sent += 1
        stamp = self.world.timestamp() if timestamp is None else timestamp
        for endpoint in list(self._endpoints):
            if endpoint is sender and not endpoint.receive_own_messages:
                continue
            endpoint._deliver(_copy(msg, stamp, self.name, is_rx=endpoint is not sender))
        if msg.is_error_frame:
            self.stats.unclaimed += 1
            return
        replies: list[Frame] = []
        claimed = self._route(
            msg.arbitration_id,
            bytes(msg.data),
            replies,
            is_extended_id=msg.is_extended_id,
            is_remote_frame=msg.is_remote_frame,
            is_fd=msg.is_fd,
        )
        if not claimed:
            self.stats.unclaimed += 1
        self.deliver_frames(replies)

    def _route(
        self,
        can_id: int,
        data: bytes,
        replies: list[Frame],
        source: SimDevice | CanNode | None = None,
        **flags: bool,
    ) -> bool:
        """Hand a frame to every motor (but its sender) listening on its id; collect replies."""
        if self._routed_count != len(self.devices) + len(self.nodes):
            self._build_routes()
        listeners = self._routes.get(can_id)
        if not listeners:
            return False
        claimed = False
        now_ns = self.world.time_ns
        for device in listeners:
            if device is not source:
                claimed = True
                replies += device.receive(can_id, data, now_ns, **flags)
        return claimed

    def _build_routes(self) -> None:
        routes: dict[int, list[SimDevice | CanNode]] = {}
        devices = [*self.devices, *self.nodes]
        for device in devices:
            for can_id in device.listen_ids:
                routes.setdefault(can_id, []).append(device)
        self._routes = {can_id: tuple(listeners) for can_id, listeners in routes.items()}
        self._routed_count = len(devices)

    def deliver_frames(self, frames: Iterable[Frame]) -> None:
        """Deliver frames sent by the motors to every attached bus."""
        frames = list(frames)
        if not frames:
            return
        with self.world.lock:
            if self._state is can.BusState.ERROR or self.closed:
                self.stats.lost += len(frames)
                return
            self.stats.device_frames += len(frames)
            stamp = self.world.timestamp()
            name = self.name
            for endpoint in self._endpoints:
                messages = [
                    can.Message(
                        timestamp=stamp,
                        arbitration_id=can_id,
                        is_extended_id=False,
                        data=data,
                        channel=name,
                        is_rx=True,
                    )
                    for can_id, data in frames
                ]
                # All at once where the bus can take them so (one lock, one wake-up of
                # its reader per tick instead of one per frame).
                deliver_all = getattr(endpoint, '_deliver_all', None)
                if deliver_all is not None:
                    deliver_all(messages)
                else:
                    for msg in messages:
                        endpoint._deliver(msg)

    def _emit(self, now_ns: int) -> None:
        sent: list[tuple[SimDevice | CanNode, Frame]] = []
        for device in (*self.devices, *self.nodes) if self.nodes else self.devices:
            frames = device.emit(now_ns)
            if frames:
                sent += [(device, frame) for frame in frames]
        if not sent:
            return
        self.deliver_frames([frame for _, frame in sent])
        if self._state is can.BusState.ERROR:
            return
        # Every node hears every frame: a motor's frame can reach another motor (only a
        # garbage frame can, the config check keeps feedback ids off command ids).
        replies: list[Frame] = []
        for device, (can_id, data) in sent:
            self._route(can_id, data, replies, device)
        self.deliver_frames(replies)


def _copy(msg: can.Message, timestamp: float, channel: str, *, is_rx: bool) -> can.Message:
    return can.Message(
        timestamp=timestamp,
        arbitration_id=msg.arbitration_id,
        is_extended_id=msg.is_extended_id,
        is_remote_frame=msg.is_remote_frame,
        is_error_frame=msg.is_error_frame,
        channel=channel,
        dlc=msg.dlc,
        data=bytes(msg.data),
        is_fd=msg.is_fd,
        is_rx=is_rx,
        bitrate_switch=msg.bitrate_switch,
        error_state_indicator=msg.error_state_indicator,
    )
