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
import heapq
import itertools
import math
import os
import threading
import time
from collections.abc import Callable, Mapping
from typing import Any

import can
from rm_base.hardware import CanHardware
from rm_base.runtime.realtime import outside_robot
from rm_base.sim import SimBus, SimWorld

from reliability.wire import WireChecker
from rm_base import motors as motor_families

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
        self.hw = CanHardware(
            self.config, clock_ns=self.now_ns, bus_factory=self._open, families=motor_families,
        )
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

    def fault(self, joint: str, fault: Any) -> None:
        """Inject a simulated fault into joint's motor and tell the checker (its own record)."""
        self.world.inject(joint, fault)
        self.checker.note_fault(joint, fault.kind.value, self.t,
                                temperature=fault.temperature)

    def clear_fault(self, joint: str, kind: Any) -> None:
        """Clear a simulated fault of joint's motor and tell the checker."""
        self.world.clear_faults(joint, kind)
        self.checker.note_fault(joint, kind.value, self.t, active=False)

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


def hardware_config(parameters: Mapping[str, Any]) -> dict[str, Any]:
    """The hardware config dict from a bridge's flat parameters (``buses.can0.channel``...).

    Keeps the hardware schema's groups (buses, joints, scheduler, safety) and drops the
    simulator's keys (``joints.<joint>.sim.*``) and the node's own parameters.
    """
    config: dict[str, Any] = {}
    for name, value in parameters.items():
        parts = name.split('.')
        if parts[0] not in ('buses', 'joints', 'scheduler', 'safety'):
            continue
        if parts[0] == 'joints' and len(parts) > 2 and parts[2] == 'sim':
            continue
        if parts[0] == 'buses' and len(parts) > 2 and parts[2] == 'log_file':
            continue
        node = config
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = list(value) if isinstance(value, tuple) else value
    return config


class WireWatch:
    """Taps every simulated bus of a running bridge and checks every frame, in a thread.

    Commands (``note_command``) arrive on the ROS executor thread and frames on the taps;
    both carry wall-clock times, and the checker must see them in time order, so the
    thread works ``lag_s`` behind real time: everything older than that is merged by time
    and checked. A starved executor delivers its commands late to the bridge too (it
    stamps them on arrival), so the two stay in step as long as the lag covers the delay.

    What waits for the lag is kept as tuples of numbers, strings and bytes, not as frames
    and command objects: a soak holds thousands of them, and the garbage collection that the
    robot's loop runs in the same process scans every container object that is alive
    (docs/RELIABILITY.md, "Soak").

    Args:
        world: the bridge's SimWorld (real time: frames carry ``time.time()``).
        config: its hardware config (see :func:`hardware_config`).
        grace_s: the checker's timing grace [s].
        record: keep per-joint timelines (tests; not for long runs).
        track_commands: apply the checker's ``no_command`` rule (feed note_command).
        lag_s: how far behind real time the checking runs [s].
        period_s: how often the thread works [s].
        stall_s: the checker's stall gap [s] (see WireChecker).
        feedback_window_s: the checker's feedback window [s] (see WireChecker): the
            feedback timeout plus the grace.
        clock: the time frames and commands are stamped with [s]; a stepped world's
            ``timestamp`` in lockstep (then there is no thread: ``sync`` checks everything
            up to the world's now).
    """

    def __init__(
        self,
        world: SimWorld,
        config: Mapping[str, Any],
        *,
        grace_s: float = 0.05,
        record: bool = False,
        track_commands: bool = False,
        lag_s: float = 0.3,
        period_s: float = 0.01,
        stall_s: float | None = 0.02,
        feedback_window_s: float = 0.15,
        clock: Callable[[], float] | None = None,
    ) -> None:
        self.checker = WireChecker(
            config,
            grace_s=grace_s,
            record=record,
            track_commands=track_commands,
            stall_s=stall_s,
            feedback_window_s=feedback_window_s,
        )
        self._taps = {
            bus: SimBus(str(cfg.get('channel', bus)), world=world, rx_queue_size=0)
            for bus, cfg in config['buses'].items()
        }
        self._lag_s = lag_s
        self._lead_s = 0.01  # [s] see _work
        # heap by time: (t, seq, bus, id, data, the frame itself only if not a data frame)
        self._frames: list[tuple[float, int, str, int, bytes, can.Message | None]] = []
        # (t, joint, mode) of a joint command; (t, message, None) of an /actuator_cmd
        self._commands: collections.deque[tuple[float, Any, int | None]] = collections.deque()
        self._seq = itertools.count()
        self._lock = threading.Lock()
        self._done_until = 0.0  # everything before this wall time has been checked
        self._stop = threading.Event()
        self._period_s = period_s
        self._clock = time.time if clock is None else clock
        self._thread: threading.Thread | None = None
        if clock is None:
            self._thread = threading.Thread(target=self._run, name='wire-watch', daemon=True)
            self._thread.start()

    def _run(self) -> None:
        with outside_robot():  # the test's, not the robot's (rm_base.runtime.realtime)
            while not self._stop.wait(self._period_s):
                self._work(time.time() - self._lag_s)

    def _work(self, horizon: float) -> None:
        with self._lock:
            for bus, tap in self._taps.items():
                while (msg := tap.recv(0.0)) is not None:
                    odd = msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id
                    heapq.heappush(self._frames, (
                        msg.timestamp, next(self._seq), bus, msg.arbitration_id,
                        bytes(msg.data), msg if odd else None,
                    ))
            frames, commands, checker = self._frames, self._commands, self.checker
            while frames and frames[0][0] <= horizon:
                t, _, bus, can_id, data, odd = heapq.heappop(frames)
                # The bridge's and this subscription's callbacks run one after the other
                # in one executor spin: a command noted just after a frame may already
                # have been applied to it.
                while commands and commands[0][0] <= t + self._lead_s:
                    self._note(*commands.popleft())
                if odd is None:
                    odd = can.Message(
                        timestamp=t, arbitration_id=can_id, data=data, is_extended_id=False
                    )
                checker.feed(bus, odd)
            while commands and commands[0][0] <= horizon:
                self._note(*commands.popleft())
            self._done_until = max(self._done_until, horizon)

    def _note(self, t: float, command: Any, mode: int | None) -> None:
        if mode is None:
            self.checker.note_command(command, t)
        else:
            self.checker.note_joint_command(command, mode, t)

    def note_command(self, msg: Any, t: float) -> None:
        """An /actuator_cmd seen at wall time t (the checker's ``no_command`` rule)."""
        self._commands.append((t, msg, None))

    def watch_commands(self, hardware: CanHardware) -> None:
        """Note every command where the bridge hands it to its hardware layer.

        Both ways in are tapped: ``set_command`` (checked fields) and ``set_target`` (the
        bridge's /actuator_cmd and the in-process plugins). A subscription of the test's
        own sees /actuator_cmd up to hundreds of ms after the bridge under CPU load
        (measured here), which is no oracle for a 100 ms rule; this sees each command when
        the hardware takes it (after the bridge's validation, which test_command_abuse.py
        checks on its own).
        """
        set_command, set_target = hardware.set_command, hardware.set_target
        commands = self._commands
        clock = self._clock

        def noted_command(name: str, mode: int, **kwargs: Any) -> None:
            set_command(name, mode, **kwargs)  # raises for a rejected one: not noted
            commands.append((clock(), name, mode))

        def noted_target(name: str, target: Any, **kwargs: Any) -> None:
            set_target(name, target, **kwargs)  # raises for an unknown joint: not noted
            commands.append((clock(), name, int(target.mode)))

        hardware.set_command = noted_command  # type: ignore[method-assign]
        hardware.set_target = noted_target  # type: ignore[method-assign]

    def sync(self, timeout: float = 10.0) -> None:
        """Wait until every frame up to now has been checked (lockstep: check them)."""
        if self._thread is None:
            self._work(self._clock())
            return
        target = time.time()
        deadline = time.monotonic() + timeout
        while self._done_until < target and time.monotonic() < deadline:
            time.sleep(self._period_s)

    def close(self) -> None:
        """Stop the thread, check everything left, close the taps."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        self._work(math.inf)
        for tap in self._taps.values():
            tap.shutdown()
