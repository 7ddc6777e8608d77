"""The simulated world: CAN channels with their motors, the robot body, serial devices, the clock.

Why one module: the clock and its stepping, which every part of the world shares; channels,
devices, the body and the serial devices (rm_base.sim.serial_devices) are modules of their
own.

One :class:`SimWorld` owns everything that moves together. It advances in fixed ticks
(1 kHz by default), either

* **stepped**: only when told (:meth:`SimWorld.step`, :meth:`SimWorld.advance`), which is
  deterministic and what tests use; or
* **real time**: a physics thread ticks at absolute deadlines on ``perf_counter_ns``
  (:meth:`SimWorld.start`), which is what a node running against ``rm_sim`` uses.

One tick: every device runs its driver logic (timeouts, internal loops), the motors step
(the gimbal yaw motor last, with the chassis' yaw acceleration), the chassis pose is
integrated, then every device sends its due feedback frames and every IMU its due frame.

Its CAN channels (:mod:`rm_base.sim.channel`) are registered by name, process-wide, like
python-can's virtual interface.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from enum import Enum
from pathlib import Path
from typing import Any

from rm_base.runtime import realtime
from rm_base.sim.body import RobotBody
from rm_base.sim.body_config import body_from_config
from rm_base.sim.channel import SimChannel, register_channel, release_channel
from rm_base.sim.device_config import check_channel, device_from_config
from rm_base.sim.image_link import SimImageLink
from rm_base.sim.imu import SimImu
from rm_base.sim.referee import SimReferee
from rm_base.sim.remote import SimRemote
from rm_base.sim.serial_devices import SerialDevice, SerialDevices
from rm_base.sim.supercap import SimSupercap, supercap_from_config
from rm_base.sim.target import SimTarget, muzzle_pose, target_from_config
from rm_base.sim_devices.device import SimDevice
from rm_base.sim_devices.errors import SimConfigError, SimLookupError, SimStateError
from rm_base.sim_devices.faults import Fault, FaultKind

LOG = logging.getLogger(__name__)

_NS_PER_S = 1_000_000_000
#: How far the real-time loop may fall behind before it stops catching up [ticks].
_MAX_LAG_TICKS = 50


class Timing(Enum):
    """Who drives the clock."""

    REALTIME = 'realtime'  # a physics thread, at wall-clock rate
    STEPPED = 'stepped'  # the caller, through step() / advance()


def _default_on_error(error: BaseException) -> bool:
    LOG.error('rm_sim physics thread stopped by an error', exc_info=error)
    return False


class SimWorld:
    """Everything simulated that shares one clock.

    Build one from a config with :meth:`from_config`, or piece by piece with
    :meth:`add_channel`, :meth:`add_motor`, :meth:`set_body`, :meth:`add_imu`,
    :meth:`set_referee`, :meth:`set_remote` and :meth:`set_image_link`; then
    either :meth:`start` its real-time thread or drive it with :meth:`step`. (A world that a
    :class:`~rm_base.sim.bus.SimBus` builds is started by the bus.) Use it as a context
    manager (or call :meth:`close`) so the physics thread stops, the serial terminals close
    and the channel names are released.

    Attributes:
        timing: who drives the clock.
        period_ns: tick length [ns].
        time_ns: simulation time [ns] since creation.
        lock: serialises physics ticks and bus traffic.
        body: the robot body (an empty one until :meth:`set_body`).
        overruns: times the real-time loop fell too far behind and skipped ahead.
        slipped_ns: wall-clock time those skips left unsimulated [ns]: simulated time
            plus this is about the wall-clock time the physics thread has run.
        error: the exception that stopped the physics thread, if any.
        serial: the devices on serial ports (:mod:`rm_base.sim.serial_devices`); also as
            :attr:`referee`, :attr:`remote`, :attr:`image_link`, :attr:`serial_sink`.
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
        self.serial = SerialDevices()
        self.lock = threading.RLock()
        self.body = RobotBody()
        self.overruns = 0
        self.slipped_ns = 0
        self.error: BaseException | None = None
        self.seed = seed
        self._on_error = on_error or _default_on_error
        self._epoch = time.time()
        self._channels: dict[str, SimChannel] = {}
        self._devices: dict[str, SimDevice] = {}
        #: The super-capacitor board, if the world has one (:meth:`set_supercap`).
        self.supercap: SimSupercap | None = None
        #: A spinning robot to shoot at, if the world has one (``target``).
        self.target: SimTarget | None = None
        self._device_channel: dict[str, SimChannel] = {}
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
            body: {...}                 # see rm_base.sim.body_config.body_from_config
            imus: [{path: '/tmp/rm_sim_${ROS_DOMAIN_ID}/imu', mount: gimbal, rate_hz: 100}]
            referee: {path: '/tmp/rm_sim_${ROS_DOMAIN_ID}/referee', chassis_power_limit: 60}
            supercap: {channel: can0, capacity_j: 2000}   # rm_base.sim.supercap
            target: {x: 4.0, v_yaw: 2.0}                  # rm_base.sim.target
            remote: {path: '/tmp/rm_sim_${ROS_DOMAIN_ID}/dr16'}
            image_link: {path: '/tmp/rm_sim_${ROS_DOMAIN_ID}/image_link'}

        Motor dicts: see :func:`rm_base.sim.device_config.device_from_config`; IMU dicts:
        :func:`rm_base.sim.imu.imu_from_config`; the referee:
        :func:`rm_base.sim.referee.referee_from_config`; the DR16:
        the DR16 (``remote``) and the image link: ``{path}``
        (:func:`rm_base.sim.operator_link.link_from_config`).

        Raises:
            SimConfigError: anything invalid; the partly built world is closed again.
        """
        config = load_config(config)
        allowed = {
            'timing', 'tick_rate_hz', 'seed', 'channels', 'body', 'imus', 'referee', 'remote',
            'image_link', 'supercap', 'target',
        }
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
            if 'supercap' in config:
                world.set_supercap(config['supercap'])
            if 'target' in config:
                world.target = target_from_config(config['target'])
            if 'referee' in config:
                world.set_referee(config['referee'])
            if 'remote' in config:
                world.set_remote(config['remote'])
            if 'image_link' in config:
                world.set_image_link(config['image_link'])
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
                channel = self._channels[name] = register_channel(self, name)
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
        """Build the robot body (see :func:`~rm_base.sim.body_config.body_from_config`).

        Raises:
            SimConfigError: invalid config or unknown motor names.
            SimStateError: a referee judges the body already.
        """
        with self.lock:
            self._check_open()
            body = body_from_config(config, self._devices)
            self.serial.set_body(body)
            self.body = body
            return body

    def add_imu(self, config: Mapping[str, Any]) -> SimImu:
        """Create an IMU on a pseudo-terminal (see :func:`~rm_base.sim.imu.imu_from_config`).

        Raises:
            SimConfigError: invalid config or a name already used.
        """
        with self.lock:
            self._check_open()
            return self.serial.add_imu(config, self.body)

    def set_referee(self, config: Mapping[str, Any]) -> SimReferee:
        """Create the referee system, judging the body set before.

        See :meth:`rm_base.sim.serial_devices.SerialDevices.set_referee`; with a
        super-capacitor board, the referee measures what the board draws.
        """
        with self.lock:
            self._check_open()
            referee = self.serial.set_referee(config, self.body)
            referee.supply = self.supercap
            return referee

    def set_supercap(self, config: Mapping[str, Any]) -> SimSupercap:
        """Put the super-capacitor board (:mod:`rm_base.sim.supercap`) on a channel.

        It feeds the body's wheels, so the body comes first.

        Raises:
            SimConfigError: invalid config, or the body has no chassis.
            SimLookupError: no such channel.
            SimStateError: the world has a board already.
        """
        with self.lock:
            self._check_open()
            if self.supercap is not None:
                raise SimStateError('the world has a super-capacitor board already')
            chassis = self.body.chassis
            if chassis is None:
                raise SimConfigError('a super-capacitor feeds the chassis: the body has none')
            cap = supercap_from_config(config, chassis.motors)
            self.channel(cap.channel).nodes.append(cap)
            self.supercap = cap
            if self.serial.referee is not None:
                self.serial.referee.supply = cap
            return cap

    def set_remote(self, config: Mapping[str, Any]) -> SimRemote:
        """Create the DR16 receiver (:class:`~rm_base.sim.remote.SimRemote`) from ``{path}``."""
        with self.lock:
            self._check_open()
            return self.serial.set_remote(config)

    def set_image_link(self, config: Mapping[str, Any]) -> SimImageLink:
        """Create the image link (:class:`~rm_base.sim.image_link.SimImageLink`), ``{path}``."""
        with self.lock:
            self._check_open()
            return self.serial.set_image_link(config)

    @property
    def referee(self) -> SimReferee | None:
        """The simulated referee system, or None."""
        return self.serial.referee

    @property
    def remote(self) -> SimRemote | None:
        """The simulated DR16 receiver, or None."""
        return self.serial.remote

    @property
    def image_link(self) -> SimImageLink | None:
        """The simulated image link (keyboard and mouse), or None."""
        return self.serial.image_link

    @property
    def serial_sink(self) -> Callable[[SerialDevice, bytes], object] | None:
        """Who takes the serial devices' frames.

        None (default): their terminals; else ``serial_sink(device, frame)``, in the
        stepping thread (lockstep).
        """
        return self.serial.sink

    @serial_sink.setter
    def serial_sink(self, sink: Callable[[SerialDevice, bytes], object] | None) -> None:
        self.serial.sink = sink

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
        return self.serial.imu(name)

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
            frames = self.serial.take()
        self.serial.write(frames)

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
        body.apply_end_stops()
        self.time_ns = now = now + self.period_ns
        if self.supercap is not None:
            self.supercap.step(now, dt)
        for channel in self._channels.values():
            channel._emit(now)
        # a device's counter runs on real time while the physics runs in real time
        device_ns = time.perf_counter_ns() if self.running else now
        launcher = body.launcher
        shots = launcher.update(now) if launcher else ()
        target = self.target
        if target is not None and shots:
            muzzle, yaw, pitch = muzzle_pose(body)
            for shot in shots:
                target.shoot(shot.time_ns, muzzle, yaw, pitch, shot.speed_mps)
        self.serial.tick(now, device_ns, dt, shots)
        for channel in self._channels.values():
            channel.flush_handed_over()

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
        with realtime.outside_robot():  # the motors are not the robot's threads
            self._run_physics()

    def _run_physics(self) -> None:
        period = self.period_ns
        deadline = time.perf_counter_ns() + period
        while not self._stop.is_set():
            try:
                with self.lock:
                    self._tick()
                    frames = self.serial.take()
                self.serial.write(frames)
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
                self.slipped_ns -= remaining
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
        """Stop the thread, close the terminals and release the channel names (idempotent)."""
        self.stop()
        with self.lock:
            if self._closed:
                return
            self._closed = True
            self.serial.close()
            for channel in self._channels.values():
                release_channel(channel)

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
