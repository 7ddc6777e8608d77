"""``rm_sim``: the python-can interface of the simulator.

``can.Bus(interface='rm_sim', channel='can0', ...)`` opens a :class:`SimBus`, registered
as the ``can.interface`` entry point ``rm_sim`` of rm_base. It implements python-can's
:class:`can.BusABC` the way ``can/interfaces/virtual.py`` does: every bus opened on the
same channel name in one process shares one simulated bus and receives every frame the
others send. On top of that the channel has simulated motors that take command frames and
send feedback frames, through the same protocol code the real drivers use.

Which world a bus joins:

1. ``world=<SimWorld>``: that world (the channel is created in it if needed);
2. the channel name is already registered: the world that owns it;
3. ``world=<dict or path to YAML>``: a new world built from that config
   (:meth:`SimWorld.from_config`), owned by the buses: it closes with the last of them.
   Passing the same config to every bus (``can0``, ``can1``) gives one shared world;
4. otherwise: a new world with just this channel and the ``motors`` given, also owned
   by the buses.

A world built here (3, 4) runs in real time unless ``timing='stepped'``; then the test
drives it with ``bus.sim.step(n)`` (ticks) or ``bus.sim.advance(seconds)``. Opening a bus
on a real-time world that is not running starts its physics thread.
"""

from __future__ import annotations

import logging
import queue
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import can
from can.typechecking import AutoDetectedConfig, CanFilters

from rm_base.sim.channel import SimChannel, channel_names, find_channel
from rm_base.sim.world import SimWorld, Timing, load_config
from rm_base.sim_devices.errors import SimConfigError

LOG = logging.getLogger(__name__)

#: Default receive queue length [frames]: about one second of a full bus at 1 kHz x 8
#: motors. A socketcan socket drops frames when its buffer is full, and so does this.
DEFAULT_RX_QUEUE_SIZE = 10_000


class _RxQueue(queue.Queue[can.Message]):
    """A receive queue that also takes a batch of frames under one lock."""

    def put_all_nowait(self, items: Sequence[can.Message]) -> int:
        """Put items in order while there is room; return how many did not fit.

        Like ``put_nowait`` for each, but the lock is taken once and the readers are
        woken once (one wake-up per item put, as ``put`` gives).
        """
        dropped = 0
        with self.not_full:
            for item in items:
                if 0 < self.maxsize <= self._qsize():
                    dropped += 1
                    continue
                self._put(item)
                self.unfinished_tasks += 1
            if len(items) > dropped:
                self.not_empty.notify(len(items) - dropped)
        return dropped


class SimBus(can.BusABC):
    """A python-can bus on a simulated CAN channel.

    Attributes:
        channel_info: ``'rm_sim channel <name>'``.
        receive_own_messages: sent frames come back to this bus too.
        rx_overflows: frames dropped because the receive queue was full.
    """

    def __init__(
        self,
        channel: str = 'can0',
        can_filters: CanFilters | None = None,
        receive_own_messages: bool = False,
        rx_queue_size: int = DEFAULT_RX_QUEUE_SIZE,
        preserve_timestamps: bool = False,
        *,
        motors: Sequence[Mapping[str, Any]] | None = None,
        world: SimWorld | Mapping[str, Any] | str | Path | None = None,
        timing: Timing | str | None = None,
        tick_rate_hz: float | None = None,
        seed: int | None = None,
        **kwargs: Any,
    ):
        """Open a bus on a simulated channel.

        Args:
            channel: channel name; buses with the same name share one bus.
            can_filters: python-can filters (see :meth:`can.BusABC.set_filters`).
            receive_own_messages: receive the frames this bus sends.
            rx_queue_size: receive queue length [frames]; 0 is unbounded. When full,
                arriving frames are dropped and counted in :attr:`rx_overflows`.
            preserve_timestamps: keep the timestamp of sent messages instead of stamping
                them with the simulation's clock.
            motors: motor dicts (see :func:`rm_base.sim.device_config.device_from_config`) to
                put on the channel; motors already there with the same config are kept.
            world: a :class:`SimWorld`, or a world config (dict or YAML/JSON path) to build
                one from when the channel does not exist yet.
            timing: ``'realtime'`` or ``'stepped'`` for a world built here (default
                real time; a world config's own ``timing`` key wins).
            tick_rate_hz: physics rate of a world built here [Hz] (default 1000).
            seed: random seed of a world built here.
            **kwargs: other python-can options (``bitrate``, ...), accepted and ignored.

        Raises:
            can.CanInitializationError: the channel or a motor config is invalid (the
                :class:`SimConfigError` is its cause).
        """
        self.channel_info = f'rm_sim channel {channel}'
        self.receive_own_messages = receive_own_messages
        self.preserve_timestamps = preserve_timestamps
        self.rx_overflows = 0
        # Frames may arrive between attach and BusABC.__init__, which sets the filters again.
        self._filters = can_filters or None
        self._queue: _RxQueue = _RxQueue(rx_queue_size)
        # A subclass that overrides _deliver gets every frame through it.
        self._batched = type(self)._deliver is SimBus._deliver
        self._open = False
        try:
            self._channel = _resolve_channel(
                str(channel), motors, world, timing=timing, tick_rate_hz=tick_rate_hz, seed=seed
            )
            self._channel.attach(self)
        except SimConfigError as err:
            raise can.CanInitializationError(f'rm_sim {channel}: {err}') from err
        self._open = True
        self.channel_id = self._channel.name
        super().__init__(
            channel=channel,
            can_filters=can_filters,
            receive_own_messages=receive_own_messages,
            **kwargs,
        )
        world_obj = self._channel.world
        if world_obj.timing is Timing.REALTIME and not world_obj.running:
            world_obj.start()

    # -- simulator access --------------------------------------------------------------------

    @property
    def sim(self) -> SimWorld:
        """The world this bus is in: step it, look up motors, inject faults."""
        return self._channel.world

    @property
    def sim_channel(self) -> SimChannel:
        """The simulated channel (devices, counters, bus-state injection)."""
        return self._channel

    # -- BusABC ------------------------------------------------------------------------------

    def _check_open(self) -> None:
        if not self._open:
            raise can.CanOperationError('cannot operate on a closed rm_sim bus')

    def _deliver(self, msg: can.Message) -> None:
        """Called by the channel with a frame for this bus."""
        # Filter on arrival, as the kernel does for socketcan: recv(timeout=0) then never
        # returns None while a matching frame waits behind a filtered-out one.
        if not self._matches_filters(msg):
            return
        try:
            self._queue.put_nowait(msg)
        except queue.Full:
            self.rx_overflows += 1

    def _deliver_all(self, msgs: Sequence[can.Message]) -> None:
        """Called by the channel with the frames of one tick, in order."""
        if not self._batched:
            for msg in msgs:
                self._deliver(msg)
            return
        if self._filters:
            msgs = [msg for msg in msgs if self._matches_filters(msg)]
        self.rx_overflows += self._queue.put_all_nowait(msgs)

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        self._check_open()
        try:
            msg = self._queue.get(block=True, timeout=timeout)
        except queue.Empty:
            return None, False
        return msg, True

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        """Put a frame on the simulated bus (``timeout`` is unused: delivery is immediate).

        Raises:
            can.CanOperationError: the bus is closed or the channel is in bus-off.
        """
        self._check_open()
        stamp = msg.timestamp if self.preserve_timestamps else None
        self._channel.send(self, msg, stamp)

    def flush_tx_buffer(self) -> None:
        """Nothing to flush: frames are delivered when sent."""
        self._check_open()

    @property
    def state(self) -> can.BusState:
        """ACTIVE, or the state injected on the channel (PASSIVE, ERROR = bus-off)."""
        return self._channel.state

    @state.setter
    def state(self, new_state: can.BusState) -> None:
        raise NotImplementedError('inject a bus state with bus.sim_channel.set_state()')

    def shutdown(self) -> None:
        """Detach from the channel (idempotent); the last bus of a bus-built world closes it."""
        super().shutdown()
        if self._open:
            self._open = False
            self._channel.detach(self)

    @staticmethod
    def _detect_available_configs() -> list[AutoDetectedConfig]:
        """The registered channels (a new name would create a new, empty channel)."""
        return [{'interface': 'rm_sim', 'channel': name} for name in channel_names()]


def _resolve_channel(
    channel: str,
    motors: Sequence[Mapping[str, Any]] | None,
    world: SimWorld | Mapping[str, Any] | str | Path | None,
    *,
    timing: Timing | str | None,
    tick_rate_hz: float | None,
    seed: int | None,
) -> SimChannel:
    if motors is not None and (isinstance(motors, str | Mapping)):
        raise SimConfigError(f'motors must be a list of motor dicts, got {motors!r}')
    if isinstance(world, SimWorld):
        if channel in world.channels:
            target = world.channel(channel)
        else:
            target = world.add_channel(channel)
        _add_motors(target, motors)
        return target
    existing = find_channel(channel)
    if existing is not None:
        _check_same(existing.world, timing, tick_rate_hz, seed)
        _add_motors(existing, motors)
        return existing
    options: dict[str, Any] = {}
    if timing is not None:
        options['timing'] = timing
    if tick_rate_hz is not None:
        options['tick_rate_hz'] = tick_rate_hz
    if seed is not None:
        options['seed'] = seed
    if world is not None:
        new_world = SimWorld.from_config({**options, **load_config(world)})
    else:
        new_world = SimWorld(**options)
    new_world._owned_by_buses = True
    try:
        target = new_world.channels.get(channel) or new_world.add_channel(channel)
        _add_motors(target, motors)
    except BaseException:
        new_world.close()
        raise
    return target


def _add_motors(channel: SimChannel, motors: Sequence[Mapping[str, Any]] | None) -> None:
    for motor in motors or ():
        channel.world.add_motor(channel.name, motor)


def _check_same(
    world: SimWorld, timing: Timing | str | None, tick_rate_hz: float | None, seed: int | None
) -> None:
    try:
        wanted = None if timing is None else Timing(timing)
    except ValueError:
        raise SimConfigError(f"timing must be 'realtime' or 'stepped', got {timing!r}") from None
    if wanted is not None and wanted is not world.timing:
        raise SimConfigError(f'the channel exists with timing {world.timing.value}, not {timing}')
    if tick_rate_hz is not None and round(1e9 / tick_rate_hz) != world.period_ns:
        raise SimConfigError(f'the channel exists with another tick rate than {tick_rate_hz} Hz')
    if seed is not None and seed != world.seed:
        raise SimConfigError(f'the channel exists with seed {world.seed}, not {seed}')
