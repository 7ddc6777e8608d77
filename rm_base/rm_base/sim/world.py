"""The simulated world: CAN channels with their motors, the robot body, IMUs, and the clock.

One :class:`SimWorld` owns everything that moves together. It advances in fixed ticks
(1 kHz by default), either

* **stepped**: only when told (:meth:`SimWorld.step`, :meth:`SimWorld.advance`), which is
  deterministic and what tests use; or
* **real time**: a physics thread ticks at absolute deadlines on ``perf_counter_ns``
  (:meth:`SimWorld.start`), which is what a node running against ``rm_sim`` uses.

One tick: every device runs its driver logic (timeouts, internal loops), the motors step
(the gimbal yaw motor last, with the chassis' yaw acceleration), the chassis pose is
integrated, then every device sends its due feedback frames and every IMU its due frame.

Channels are registered by name in a process-wide registry, like python-can's virtual
interface: every :class:`~rm_base.sim.bus.SimBus` opened on a channel name attaches to the
same :class:`SimChannel`, sees every frame the other buses send, and every frame the
channel's motors send. A channel belongs to exactly one world.
"""

from __future__ import annotations

import collections
import contextlib
import copy
import logging
import math
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Any, Protocol

import can

from rm_base.sim.body import RobotBody, body_from_config
from rm_base.sim.device_config import check_channel, device_from_config
from rm_base.sim.devices import Frame, SimDevice
from rm_base.sim.errors import SimConfigError, SimLookupError, SimStateError
from rm_base.sim.faults import Fault, FaultKind
from rm_base.sim.imu import SimImu, imu_from_config

LOG = logging.getLogger(__name__)

_NS_PER_S = 1_000_000_000
#: How far the real-time loop may fall behind before it stops catching up [ticks].
_MAX_LAG_TICKS = 50


class Timing(Enum):
    """Who drives the clock."""

    REALTIME = 'realtime'  # a physics thread, at wall-clock rate
    STEPPED = 'stepped'  # the caller, through step() / advance()


class _Endpoint(Protocol):
    """What a channel needs from an attached bus (implemented by SimBus).

    An endpoint may also have ``_deliver_all(msgs)``, taking a tick's frames at once.
    """

    receive_own_messages: bool

    def _deliver(self, msg: can.Message) -> None: ...


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


class SimChannel:
    """One simulated CAN bus: its motors and the python-can buses attached to it.

    Attributes:
        name: channel name (``'can0'``).
        world: the world it belongs to.
        devices: the motors on it, in config order.
        stats: frame counters.
    """

    def __init__(self, world: SimWorld, name: str):
        self.name = name
        self.world = world
        self.devices: list[SimDevice] = []
        self.stats = ChannelStats()
        self._endpoints: list[_Endpoint] = []
        self._state = can.BusState.ACTIVE
        self.closed = False
        # can id -> the devices listening on it, in device order; built for _routed_count
        # devices (the list only grows, through SimWorld.add_motor)
        self._routes: dict[int, tuple[SimDevice, ...]] = {}
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
            timestamp: timestamp for the copies [s]; None uses the world's clock.

        Raises:
            can.CanOperationError: the channel is closed or in (injected) bus-off.
        """
        lock = self.world.lock
        if not lock.acquire(blocking=False):
            if not self._can_hand_over():
                lock.acquire()
            else:
                # Waiting for the physics tick's lock would cost the sender the GIL; hand
                # the frame (a copy) to the tick, which sends it before it lets go.
                self._handed_over.append((sender, copy.copy(msg), timestamp))
                if not lock.acquire(blocking=False):
                    return
                msg = None  # the tick ended meanwhile: the flush below sends it, in order
        try:
            self.flush_handed_over()
            if msg is not None:
                self._send_locked(sender, msg, timestamp)
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
        source: SimDevice | None = None,
        **flags: bool,
    ) -> bool:
        """Hand a frame to every motor (but its sender) listening on its id; collect replies."""
        if self._routed_count != len(self.devices):
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
        routes: dict[int, list[SimDevice]] = {}
        devices = list(self.devices)
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
        sent: list[tuple[SimDevice, Frame]] = []
        for device in self.devices:
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


def _default_on_error(error: BaseException) -> bool:
    LOG.error('rm_sim physics thread stopped by an error', exc_info=error)
    return False


class SimWorld:
    """Everything simulated that shares one clock.

    Build one from a config with :meth:`from_config`, or piece by piece with
    :meth:`add_channel`, :meth:`add_motor`, :meth:`set_body` and :meth:`add_imu`; then
    either :meth:`start` its real-time thread or drive it with :meth:`step`. (A world that a
    :class:`~rm_base.sim.bus.SimBus` builds is started by the bus.) Use it as a context
    manager (or call :meth:`close`) so the physics thread stops, the IMU terminals close and
    the channel names are released.

    Attributes:
        timing: who drives the clock.
        period_ns: tick length [ns].
        time_ns: simulation time [ns] since creation.
        lock: serialises physics ticks and bus traffic.
        body: the robot body (an empty one until :meth:`set_body`).
        overruns: times the real-time loop fell too far behind and skipped ahead.
        error: the exception that stopped the physics thread, if any.
        imu_sink: None (default): every IMU frame goes to its terminal; else
            ``imu_sink(imu, frame)`` takes it instead, in the stepping thread (lockstep:
            a terminal delivers to its reader asynchronously).
    """

    def __init__(
        self,
        *,
        timing: Timing | str = Timing.REALTIME,
        tick_rate_hz: float = 1000.0,
        seed: int = 0,
        on_error: Callable[[BaseException], bool] | None = None,
    ):
        """Create an empty world.

        Args:
            timing: ``'realtime'`` (default; the physics thread runs after :meth:`start`)
                or ``'stepped'``.
            tick_rate_hz: physics rate [Hz]; 1000 is the design point.
            seed: seed of every random generator (garbage frames), for repeatable runs.
            on_error: called with an exception raised inside the physics thread; return
                True to keep running. Default: log it and stop.

        Raises:
            SimConfigError: bad timing or rate.
        """
        try:
            self.timing = Timing(timing)
        except ValueError:
            raise SimConfigError(
                f"timing must be 'realtime' or 'stepped', got {timing!r}"
            ) from None
        if not (isinstance(tick_rate_hz, int | float) and math.isfinite(tick_rate_hz)):
            raise SimConfigError(f'tick_rate_hz must be a number, got {tick_rate_hz!r}')
        if not 10.0 <= tick_rate_hz <= 100_000.0:
            raise SimConfigError(f'tick_rate_hz must be 10..100000 Hz, got {tick_rate_hz}')
        if isinstance(seed, bool) or not isinstance(seed, int):
            raise SimConfigError(f'seed must be an int, got {seed!r}')
        self.period_ns = round(_NS_PER_S / tick_rate_hz)
        self.time_ns = 0
        self.imu_sink: Callable[[SimImu, bytes], object] | None = None
        self.lock = threading.RLock()
        self.body = RobotBody()
        self.overruns = 0
        self.error: BaseException | None = None
        self.seed = seed
        self._on_error = on_error or _default_on_error
        self._epoch = time.time()
        self._channels: dict[str, SimChannel] = {}
        self._devices: dict[str, SimDevice] = {}
        self._device_channel: dict[str, SimChannel] = {}
        self._imus: dict[str, SimImu] = {}
        self._imu_frames: list[tuple[SimImu, bytes]] = []
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._bus_refs = 0
        self._owned_by_buses = False
        self._closed = False

    # -- building --------------------------------------------------------------------------

    @classmethod
    def from_config(cls, config: Mapping[str, Any] | str | Path) -> SimWorld:
        """Build a world from a plain dict (or a YAML/JSON file holding one).

        Schema::

            timing: realtime            # or stepped
            tick_rate_hz: 1000
            seed: 0
            channels:                   # channel name -> list of motor dicts
              can0: [{type: m3508, id: 1, name: wheel_fl, load_inertia: 0.002}, ...]
              can1: [{type: gm6020, id: 1, name: yaw}, {type: dm4310, id: 2, name: pitch}]
            body: {...}                 # see rm_base.sim.body.body_from_config
            imus: [{path: '/tmp/rm_sim_${ROS_DOMAIN_ID}/imu', mount: gimbal, rate_hz: 100}]

        Motor dicts: see :func:`rm_base.sim.device_config.device_from_config`; IMU dicts:
        :func:`rm_base.sim.imu.imu_from_config`.

        Raises:
            SimConfigError: anything invalid; the partly built world is closed again.
        """
        config = load_config(config)
        allowed = {'timing', 'tick_rate_hz', 'seed', 'channels', 'body', 'imus'}
        unknown = sorted(set(config) - allowed)
        if unknown:
            raise SimConfigError(f'world: unknown key(s) {unknown}; known: {sorted(allowed)}')
        world = cls(
            timing=config.get('timing', Timing.REALTIME),
            tick_rate_hz=config.get('tick_rate_hz', 1000.0),
            seed=config.get('seed', 0),
        )
        try:
            channels = config.get('channels', {})
            if not isinstance(channels, Mapping):
                raise SimConfigError(f'channels must map names to motor lists, got {channels!r}')
            for name, motors in channels.items():
                world.add_channel(name, motors or ())
            if 'body' in config:
                world.set_body(config['body'])
            imus = config.get('imus', ())
            if not isinstance(imus, Sequence) or isinstance(imus, str):
                raise SimConfigError(f'imus must be a list, got {imus!r}')
            for imu in imus:
                world.add_imu(imu)
        except BaseException:
            world.close()
            raise
        return world

    def add_channel(self, name: str, motors: Iterable[Mapping[str, Any]] = ()) -> SimChannel:
        """Create (or extend) a channel and register its name process-wide.

        Raises:
            SimConfigError: the name belongs to another world, or a motor is invalid.
        """
        if not isinstance(name, str) or not name:
            raise SimConfigError(f'a channel name must be a non-empty string, got {name!r}')
        if isinstance(motors, str | Mapping):
            raise SimConfigError(f'channel {name}: motors must be a list, got {motors!r}')
        with self.lock:
            self._check_open()
            channel = self._channels.get(name)
            if channel is None:
                with _registry_lock:
                    if name in _registry:
                        raise SimConfigError(
                            f'channel {name!r} already belongs to another simulated world'
                        )
                    channel = SimChannel(self, name)
                    _registry[name] = channel
                self._channels[name] = channel
            for motor in motors:
                self.add_motor(name, motor)
            return channel

    def add_motor(self, channel: str, config: Mapping[str, Any]) -> SimDevice:
        """Add one motor (see :func:`~rm_base.sim.device_config.device_from_config`) to a channel.

        Adding a motor whose name already exists with an identical config is a no-op that
        returns the existing motor (so several buses can pass the same motor list).

        Raises:
            SimConfigError: invalid config, a name used by another motor, or an id clash.
            SimLookupError: no such channel.
        """
        with self.lock:
            self._check_open()
            ch = self.channel(channel)
            name = config.get('name') if isinstance(config, Mapping) else None
            device = device_from_config(config, seed=self.seed * 1_000_003 + len(self._devices))
            existing = self._devices.get(device.name)
            if existing is not None:
                if self._device_channel[existing.name] is ch and existing.config == dict(config):
                    return existing
                raise SimConfigError(f'a different motor is already named {name or device.name!r}')
            device.config = dict(config)
            check_channel([*ch.devices, device])
            ch.devices.append(device)
            self._devices[device.name] = device
            self._device_channel[device.name] = ch
            return device

    def set_body(self, config: Mapping[str, Any]) -> RobotBody:
        """Build the robot body (see :func:`~rm_base.sim.body.body_from_config`).

        Raises:
            SimConfigError: invalid config or unknown motor names.
        """
        with self.lock:
            self._check_open()
            self.body = body_from_config(config, self._devices)
            for imu in self._imus.values():
                imu.body = self.body
            return self.body

    def add_imu(self, config: Mapping[str, Any]) -> SimImu:
        """Create an IMU on a pseudo-terminal (see :func:`~rm_base.sim.imu.imu_from_config`).

        Raises:
            SimConfigError: invalid config or a name already used.
        """
        with self.lock:
            self._check_open()
            name = config.get('name', 'imu') if isinstance(config, Mapping) else None
            if name in self._imus:
                raise SimConfigError(f'two IMUs are named {name!r}')
            imu = imu_from_config(config, self.body)
            self._imus[imu.name] = imu
            return imu

    # -- lookup ----------------------------------------------------------------------------

    def channel(self, name: str) -> SimChannel:
        """The channel of that name.

        Raises:
            SimLookupError: no such channel in this world.
        """
        try:
            return self._channels[name]
        except KeyError:
            raise SimLookupError(
                f'no channel {name!r} in this world; channels: {sorted(self._channels)}'
            ) from None

    @property
    def channels(self) -> dict[str, SimChannel]:
        """Channels by name (a copy)."""
        return dict(self._channels)

    def motor(self, name: str) -> SimDevice:
        """The motor of that name.

        Raises:
            SimLookupError: no such motor.
        """
        try:
            return self._devices[name]
        except KeyError:
            raise SimLookupError(
                f'no motor {name!r} in this world; motors: {sorted(self._devices)}'
            ) from None

    @property
    def motors(self) -> dict[str, SimDevice]:
        """Motors by name (a copy)."""
        return dict(self._devices)

    def imu(self, name: str = 'imu') -> SimImu:
        """The IMU of that name.

        Raises:
            SimLookupError: no such IMU.
        """
        try:
            return self._imus[name]
        except KeyError:
            raise SimLookupError(f'no IMU {name!r}; IMUs: {sorted(self._imus)}') from None

    # -- faults ------------------------------------------------------------------------------

    def inject(self, motor: str, fault: Fault | Mapping[str, Any]) -> None:
        """Inject a fault into a motor (a :class:`Fault` or its dict form).

        Raises:
            SimLookupError: no such motor.
            SimConfigError: an invalid fault dict.
        """
        if isinstance(fault, Mapping):
            fault = Fault.from_config(fault)
        with self.lock:
            self.motor(motor).inject(fault)

    def clear_faults(self, motor: str | None = None, kind: FaultKind | str | None = None) -> None:
        """Clear one kind of fault (or all) on one motor (or all motors).

        Raises:
            SimLookupError: no such motor.
            SimConfigError: unknown fault kind.
        """
        if kind is not None:
            try:
                kind = FaultKind(kind)
            except ValueError:
                raise SimConfigError(f'unknown fault kind {kind!r}') from None
        with self.lock:
            devices = self._devices.values() if motor is None else [self.motor(motor)]
            for device in devices:
                device.clear_faults(kind)

    # -- clock -------------------------------------------------------------------------------

    @property
    def period(self) -> float:
        """Tick length [s]."""
        return self.period_ns / _NS_PER_S

    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return self.time_ns / _NS_PER_S

    def timestamp(self) -> float:
        """Timestamp for frames [s since the epoch].

        Real time: wall-clock ``time.time()``. Stepped: the creation time plus the
        simulation time, so stamps advance exactly with :meth:`step`.
        """
        if self.running:
            return time.time()
        return self._epoch + self.time_ns / _NS_PER_S

    def step(self, n: int = 1) -> None:
        """Advance the world by n ticks (stepped use).

        Raises:
            SimStateError: the real-time thread is running, or the world is closed.
            ValueError: n < 0.
        """
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise ValueError(f'n must be an int >= 0, got {n!r}')
        with self.lock:
            self._check_open()
            if self.running:
                raise SimStateError('the real-time physics thread owns the clock; stop() it first')
            for _ in range(n):
                self._tick()
            imu_frames = self._take_imu_frames()
        self._write_imu_frames(imu_frames)

    def advance(self, seconds: float) -> None:
        """Advance the world by ``seconds`` [s], rounded to whole ticks.

        Raises:
            SimStateError: the real-time thread is running, or the world is closed.
            ValueError: seconds negative or not finite.
        """
        if not (math.isfinite(seconds) and seconds >= 0.0):
            raise ValueError(f'seconds must be finite and >= 0, got {seconds!r}')
        self.step(round(seconds * _NS_PER_S / self.period_ns))

    def _tick(self) -> None:
        dt = self.period_ns / _NS_PER_S
        now = self.time_ns
        devices = list(self._devices.values())
        for device in devices:
            device.control(now, dt)
        body = self.body
        body.apply_loads()
        late = body.late_devices
        for device in devices:
            if device not in late:
                device.step(dt)
        body.update_chassis(dt)
        for device in late:
            device.step(dt, body.yaw_acceleration)
        self.time_ns = now = now + self.period_ns
        for channel in self._channels.values():
            channel._emit(now)
        # a device's counter runs on real time while the physics runs in real time
        device_ns = time.perf_counter_ns() if self.running else now
        for imu in self._imus.values():
            frame = imu.poll(now, device_ns)
            if frame is not None:
                self._imu_frames.append((imu, frame))
        for channel in self._channels.values():
            channel.flush_handed_over()

    # The IMU frames of a tick are built under the lock (they read the body) but written
    # to their terminals after it is released: a terminal write is a system call that can
    # take milliseconds on a loaded machine, and every bus send waits for this lock.
    def _take_imu_frames(self) -> list[tuple[SimImu, bytes]]:
        frames, self._imu_frames = self._imu_frames, []
        return frames

    def _write_imu_frames(self, frames: list[tuple[SimImu, bytes]]) -> None:
        sink = self.imu_sink
        for imu, frame in frames:
            if sink is None:
                imu.write(frame)
            else:
                sink(imu, frame)

    # -- real time ---------------------------------------------------------------------------

    @property
    def running(self) -> bool:
        """True while the real-time physics thread runs."""
        thread = self._thread
        return thread is not None and thread.is_alive()

    def start(self) -> None:
        """Start the real-time physics thread (no-op if it runs).

        Raises:
            SimStateError: the world is stepped or closed.
        """
        with self.lock:
            self._check_open()
            if self.timing is not Timing.REALTIME:
                raise SimStateError('a stepped world has no physics thread')
            if self.running:
                return
            self._stop.clear()
            self.error = None
            self._thread = threading.Thread(target=self._run, name='rm_sim-physics', daemon=True)
            self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        """Stop the physics thread and wait up to ``timeout`` [s] for it (idempotent)."""
        thread = self._thread
        self._stop.set()
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout)
        self._thread = None

    def _run(self) -> None:
        period = self.period_ns
        deadline = time.perf_counter_ns() + period
        while not self._stop.is_set():
            try:
                with self.lock:
                    self._tick()
                    imu_frames = self._take_imu_frames()
                self._write_imu_frames(imu_frames)
            except Exception as error:
                self.error = error
                if not self._on_error(error):
                    return
            remaining = deadline - time.perf_counter_ns()
            if remaining > 0:
                # A plain sleep (at most a period, so stop() still returns within one):
                # Event.wait costs ~13 µs more CPU per tick in its Python-level locking.
                time.sleep(remaining / _NS_PER_S)
            elif -remaining > _MAX_LAG_TICKS * period:
                # Too far behind (CPU starved): let simulation time slip instead of
                # bursting hundreds of ticks.
                self.overruns += 1
                deadline = time.perf_counter_ns()
            deadline += period

    # -- life cycle --------------------------------------------------------------------------

    def _check_open(self) -> None:
        if self._closed:
            raise SimStateError('the simulated world is closed')

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._closed

    def close(self) -> None:
        """Stop the thread, close the IMUs and release the channel names (idempotent)."""
        self.stop()
        with self.lock:
            if self._closed:
                return
            self._closed = True
            for imu in self._imus.values():
                imu.close()
            with _registry_lock:
                for name, channel in self._channels.items():
                    channel.closed = True
                    if _registry.get(name) is channel:
                        del _registry[name]

    def __enter__(self) -> SimWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # Buses that create a world own it: it closes with the last of them.
    def _bus_attached(self) -> None:
        self._bus_refs += 1

    def _bus_detached(self) -> None:
        with self.lock:
            self._bus_refs -= 1
            last = self._owned_by_buses and self._bus_refs <= 0
        if last:
            self.close()


def load_config(config: Mapping[str, Any] | str | Path) -> Mapping[str, Any]:
    """Return a world config: the mapping itself, or the one in a YAML/JSON file.

    Raises:
        SimConfigError: the file cannot be read or does not hold a mapping.
    """
    if isinstance(config, Mapping):
        return config
    if not isinstance(config, str | Path):
        raise SimConfigError(f'a world config must be a mapping or a file path, got {config!r}')
    import yaml

    try:
        data = yaml.safe_load(Path(config).read_text(encoding='utf-8'))
    except (OSError, yaml.YAMLError) as err:
        raise SimConfigError(f'cannot read world config {config}: {err}') from err
    if not isinstance(data, Mapping):
        raise SimConfigError(f'world config {config} does not hold a mapping')
    return data
