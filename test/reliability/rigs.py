"""Rigs of the fault suite: the CAN hardware layer on rm_sim, in lockstep or in real time.

:class:`LockstepRig` runs :class:`~rm_base.hardware.CanHardware` against a *stepped*
simulated world with no threads at all: each millisecond the world ticks (the motors send
their feedback), every frame that arrived is dispatched at the world's time, the
hardware ticks (update, pack, send) and a tap hands every frame on the wire to a
:class:`~reliability.wire.WireChecker`. Time is exact, so a test can assert "zero within
100 ms + one tick" without any tolerance for CPU load.

:class:`FlakyAdapter` builds rm_sim buses that fail on demand like a real adapter: the
USB device disappears (send and receive raise), the transmit buffer stays full (send
raises), or the device cannot be opened for a number of attempts.
"""

from __future__ import annotations

import collections
import itertools
import os
import threading
from collections.abc import Mapping
from typing import Any

import can
from rm_base.hardware import CanHardware
from rm_base.sim import SimBus, SimWorld

from reliability.wire import WireChecker

NS_PER_MS = 1_000_000
_channels = itertools.count()


def unique_channel(tag: str) -> str:
    """An rm_sim channel name no other test in this process uses."""
    return f'rm-rel-{tag}-{os.getpid()}-{next(_channels)}'


class LockstepRig:
    """CanHardware on a stepped SimWorld, one millisecond per :meth:`step` (see module doc).

    Args:
        joints: hardware joint configs (name -> dict); every joint is on bus ``can0``.
        motors: simulated motor configs (each with ``name``); default one per joint, of
            the joint's type and id.
        safety: the hardware ``safety`` group.
        grace_s: the checker's grace [s]; one tick by default.
    """

    def __init__(
        self,
        joints: Mapping[str, Mapping[str, Any]],
        *,
        motors: list[dict[str, Any]] | None = None,
        safety: Mapping[str, float] | None = None,
        grace_s: float = 0.001,
    ) -> None:
        self.channel = unique_channel('lockstep')
        self.world = SimWorld(timing='stepped')
        if motors is None:
            motors = [{'type': j['type'], 'id': j['id'], 'name': n} for n, j in joints.items()]
        self.world.add_channel(self.channel, motors)
        self.config = {
            'buses': {'can0': {'interface': 'rm_sim', 'channel': self.channel}},
            'joints': {n: {'bus': 'can0', **j} for n, j in joints.items()},
            'safety': dict(safety or {}),
        }
        self._sim_buses: list[SimBus] = []
        self.hw = CanHardware(self.config, clock_ns=self.now_ns, bus_factory=self._open)
        self.tap = SimBus(self.channel, world=self.world, rx_queue_size=0)
        self.peer = SimBus(self.channel, world=self.world, rx_queue_size=0)
        self.checker = WireChecker(self.config, grace_s=grace_s, record=True)
        self.wire: list[can.Message] = []  # every frame seen, oldest first
        # frames the hardware sent, in order, not yet seen by the tap: tells its frames
        # from those of other nodes (injected frames, simulated garbage)
        self._sent: collections.deque[tuple[int, bytes]] = collections.deque()
        self.bus = self.hw.buses['can0']
        self.bus.open()  # no receive thread: step() dispatches

    def _open(self, interface: str, channel: str, ignore_config: bool = True, **kwargs: Any):
        assert interface == 'rm_sim'
        kwargs.pop('bitrate', None)
        bus = _RecordingSimBus(self._sent, channel=channel, world=self.world, **kwargs)
        self._sim_buses.append(bus)
        return bus

    def now_ns(self) -> int:
        """The hardware's clock: the world's time [ns]."""
        return self.world.time_ns

    @property
    def t(self) -> float:
        """Wire time of the current tick [s] (the stamp of this tick's frames)."""
        return self.world.timestamp()

    def close(self) -> None:
        """Shut everything down (zero frames first) and free the channel."""
        self.hw.shutdown()
        self.tap.shutdown()
        self.peer.shutdown()
        self.world.close()

    def step(self, n: int = 1, commands: Mapping[str, Mapping[str, Any]] | None = None) -> None:
        """Run n milliseconds; set ``commands`` (joint -> set_command kwargs) every tick."""
        for _ in range(n):
            self.world.step(1)
            now = self.world.time_ns
            self._receive(now)  # this tick's feedback
            for joint, kwargs in (commands or {}).items():
                self.hw.set_command(joint, now_ns=now, **kwargs)
            self.hw.tick(now)
            self._receive(now)  # replies to this tick's commands (MIT motors answer at once)
            self.drain()

    def _receive(self, now_ns: int) -> None:
        bus = self._sim_buses[-1]
        while (msg := bus.recv(0.0)) is not None:
            self.bus.dispatch(msg, now_ns)

    def inject(self, can_id: int, data: bytes) -> None:
        """Put a frame from another node on the wire (seen by the hardware next step)."""
        self.peer.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))

    def drain(self) -> None:
        """Hand every frame the tap saw to the checker, marking the hardware's own."""
        while (msg := self.tap.recv(0.0)) is not None:
            self.wire.append(msg)
            sent = self._sent
            own = bool(sent) and sent[0] == (msg.arbitration_id, bytes(msg.data))
            if own:
                sent.popleft()
            self.checker.feed('can0', msg, from_bridge=own)

    def frames(self, can_id: int) -> list[can.Message]:
        """Every frame with this id seen so far."""
        return [m for m in self.wire if m.arbitration_id == can_id]


class _RecordingSimBus(SimBus):
    """An rm_sim bus that notes every frame it puts on the wire."""

    def __init__(self, sent: collections.deque[tuple[int, bytes]], **kwargs: Any) -> None:
        self._record = sent
        super().__init__(**kwargs)

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        super().send(msg, timeout)
        self._record.append((msg.arbitration_id, bytes(msg.data)))


class FlakyAdapter:
    """A bus factory for rm_sim whose buses fail on demand (see the module docstring).

    Attributes:
        gone: set -> send and receive raise ``CanOperationError`` (adapter unplugged).
        tx_full: set -> send raises ``CanOperationError`` (transmit buffer full).
        refuse_opens: that many next opens raise ``CanInitializationError``.
        opens: successful opens so far.
        refused: opens refused so far.
    """

    def __init__(self, world: SimWorld) -> None:
        self.world = world
        self.gone = threading.Event()
        self.tx_full = threading.Event()
        self.refuse_opens = 0
        self.opens = 0
        self.refused = 0
        self._lock = threading.Lock()

    def __call__(self, interface: str, channel: str, ignore_config: bool = True, **kwargs: Any):
        """Open a bus, or refuse to."""
        with self._lock:
            if self.refuse_opens > 0:
                self.refuse_opens -= 1
                self.refused += 1
                raise can.CanInitializationError(f'{channel}: no such device')
            self.opens += 1
        kwargs.pop('bitrate', None)
        return _FlakySimBus(self, channel=channel, world=self.world, **kwargs)


class _FlakySimBus(SimBus):
    def __init__(self, adapter: FlakyAdapter, **kwargs: Any) -> None:
        self._adapter = adapter
        super().__init__(**kwargs)

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        if self._adapter.gone.is_set():
            raise can.CanOperationError('adapter gone (injected)')
        return super()._recv_internal(timeout)

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if self._adapter.gone.is_set():
            raise can.CanOperationError('adapter gone (injected)')
        if self._adapter.tx_full.is_set():
            raise can.CanOperationError('Transmit buffer full (injected)')
        super().send(msg, timeout)
