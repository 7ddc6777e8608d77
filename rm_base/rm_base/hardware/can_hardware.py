"""CanHardware: buses + actuators + command groups + scheduler, built from one config dict.

This is the whole CAN layer behind one object; the ROS bridge node is a thin wrapper::

    hw = CanHardware(config, families=rm_base.motors)   # schema: rm_base.hardware.config
    hw.start()                             # buses up, receive threads, 1 kHz scheduler
    hw.set_command('yaw', MODE_POSITION, position=0.3)
    hw.states()                            # [JointState(...)], ActuatorState fields
    hw.diagnostics()                       # bus load/errors, overruns, period stats
    hw.shutdown()                          # zero frames, then close (idempotent)

Tests drive it without the scheduler thread: ``hw.open()`` then ``hw.tick(now_ns)``;
with ``receive_in_loop`` the buses have no receive threads and each tick begins by taking
every frame received since the last one (the ``feedback`` stage), which makes the whole
tick deterministic on a simulated clock (lockstep).
The simulator plugs in as ``interface: rm_sim`` in a bus config (``virtual`` works too).

The motor families (which actuator class a joint ``type`` is, which frames its family
shares) are handed in as ``families``: the registry, ``rm_base.motors``, lives in a layer
above this one (its families are built on the actuators here), so it is injected, never
imported.
"""

from __future__ import annotations

import functools
import logging
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import can

from rm_base.control import ChassisPowerModel
from rm_base.errors import ConfigError
from rm_base.hardware.actuators import Actuator, HoldReason, JointState, MitActuator
from rm_base.hardware.bus import BusFactory, ManagedBus
from rm_base.hardware.can_link import LinkReader, LinkReport
from rm_base.hardware.config import HardwareConfig
from rm_base.hardware.errors import CommandRejectedError, HardwareConfigError
from rm_base.hardware.families import GroupBuilder, MotorFamilies
from rm_base.hardware.power_stage import PowerLimitStage
from rm_base.hardware.protocols.mit import SystemCommand
from rm_base.hardware.protocols.supercap import COMMAND_ID as SUPERCAP_COMMAND_ID
from rm_base.hardware.supercap import Supercap
from rm_base.joints import JointTarget
from rm_base.loop.data import JOINT_STATES
from rm_base.loop.scheduler import Packer, Scheduler

_log = logging.getLogger(__name__)


class CanHardware:
    """The CAN hardware layer of one robot (see the module docstring)."""

    def __init__(
        self,
        config: Mapping[str, Any] | HardwareConfig,
        *,
        families: MotorFamilies,
        clock_ns: Callable[[], int] = time.perf_counter_ns,
        bus_factory: BusFactory = can.Bus,
        on_error: Callable[[Exception], bool] | None = None,
        receive_in_loop: bool | None = None,
    ) -> None:
        """Build everything; nothing is opened until :meth:`open` or :meth:`start`.

        Args:
            config: a config dict (schema in :mod:`rm_base.hardware.config`) or a parsed
                :class:`HardwareConfig`.
            families: the motor families' registry (the module ``rm_base.motors``).
            clock_ns: monotonic clock [ns] shared by feedback stamps, commands and ticks.
            bus_factory: builds python-can buses (``can.Bus``).
            on_error: scheduler error hook (return True to go on); the default logs, counts
                and goes on.
            receive_in_loop: take received frames in the loop (first stage of every tick)
                instead of a receive thread per bus; default the config's
                ``scheduler.receive_in_loop``.

        Raises:
            HardwareConfigError: anything wrong in the config, naming where.
        """
        if not isinstance(config, HardwareConfig):
            config = HardwareConfig.from_dict(config)
        self.config = config
        self._clock_ns = clock_ns
        self._closed = False
        self._unknown_joint_commands = 0
        self.buses: dict[str, ManagedBus] = {
            b.name: ManagedBus(b, clock_ns=clock_ns, bus_factory=bus_factory) for b in config.buses
        }
        # the kernel's view of each SocketCAN bus, for /diagnostics (read off the loop)
        self._links = LinkReader()
        self.actuators: dict[str, Actuator] = {}
        # families whose motors share command frames pack them through their groups
        grouped: dict[str, tuple[GroupBuilder, list[Actuator]]] = {}
        own_frames: list[Actuator] = []
        for joint in config.joints:
            try:
                family = families.family_of(joint.type)
            except ConfigError as err:  # the registry's UnknownTypeError
                raise HardwareConfigError(f'joints.{joint.name}.{err}') from None
            actuator = families.actuator_class(joint.type)(joint, config.safety)
            self.actuators[joint.name] = actuator
            if family.build_groups is None:
                own_frames.append(actuator)
            else:
                grouped.setdefault(family.name, (family.build_groups, []))[1].append(actuator)
        actuators = list(self.actuators.values())
        self.groups = [g for build, members in grouped.values() for g in build(members)]
        #: The super-capacitor controller, if the config has one.
        self.supercap = (
            Supercap(config.supercap, config.rate_hz) if config.supercap is not None else None
        )
        self._check_ids(own_frames)
        for a in actuators:
            bus = self.buses[a.bus_name]
            for fid in a.feedback_ids():
                bus.add_handler(fid, a.handle_frame)
        for name, bus in self.buses.items():
            members = [a for a in actuators if a.bus_name == name]
            bus.add_failure_listener(functools.partial(self._bus_down, members))
            bus.add_reopen_listener(functools.partial(self._bus_recovered, members))
        # A tick's frames are collected per bus and sent together (one driver call per bus
        # where the interface takes several frames at once).
        self._outgoing: dict[str, list[can.Message]] = {name: [] for name in self.buses}
        packers: list[tuple[Packer, Callable[[can.Message], None]]] = [
            (g, self._outgoing[g.bus_name].append) for g in self.groups
        ]
        packers += [(a, self._outgoing[a.bus_name].append) for a in own_frames]
        if self.supercap is not None:
            cap_bus = self.buses[self.supercap.bus_name]
            for fid in self.supercap.feedback_ids():
                cap_bus.add_handler(fid, self.supercap.handle_frame)
            packers.append((self.supercap, self._outgoing[self.supercap.bus_name].append))
        self.scheduler = Scheduler(
            actuators,
            packers,
            rate_hz=config.rate_hz,
            on_error=on_error if on_error is not None else self._log_and_go_on,
            clock_ns=clock_ns,
            flush=self._send_outgoing,
            priority=config.priority,
            collect_garbage=config.collect_garbage,
        )
        self.power_limits: dict[str, PowerLimitStage] = {}
        self.receive_in_loop = (
            config.receive_in_loop if receive_in_loop is None else receive_in_loop
        )
        if self.receive_in_loop:
            self.scheduler.add_stage(_FeedbackStage(tuple(self.buses.values())))
        for bus in self.buses.values():
            self.scheduler.add_after_tick(bus.after_tick)

    def _check_ids(self, own_frames: list[Actuator]) -> None:
        sent: dict[tuple[str, int], str] = {
            (g.bus_name, g.arbitration_id): g.name for g in self.groups
        }
        if self.supercap is not None:
            sent[(self.supercap.bus_name, SUPERCAP_COMMAND_ID)] = 'the supercap'
        replies: dict[tuple[str, str], str] = {}
        for a in own_frames:
            key = (a.bus_name, a.command_id)
            if key in sent:
                raise HardwareConfigError(
                    f'{a.name} and {sent[key]} both send frame 0x{a.command_id:03X} on {a.bus_name}'
                )
            sent[key] = a.name
            reply_key = a.reply_key()
            if reply_key is not None:
                reply = (a.bus_name, reply_key)
                if reply in replies:
                    raise HardwareConfigError(
                        f'{a.name} and {replies[reply]} both reply with {reply_key} on '
                        f'{a.bus_name}: their feedback cannot be told apart'
                    )
                replies[reply] = a.name

    def _send_outgoing(self) -> None:
        for name, frames in self._outgoing.items():
            if frames:
                self.buses[name].send_many(frames)
                frames.clear()

    @staticmethod
    def _bus_down(members: list[Actuator], now_ns: int) -> None:
        for a in members:
            a.notify_bus_down(now_ns)

    @staticmethod
    def _bus_recovered(members: list[Actuator], now_ns: int) -> None:
        for a in members:
            a.notify_bus_recovered(now_ns)

    @staticmethod
    def _log_and_go_on(exc: Exception) -> bool:
        # the scheduler has logged the exception already; the joints hold safe outputs
        return True

    # --- life cycle ---
    def open(self) -> None:
        """Open every bus and start its receive thread (no scheduler thread).

        A bus that cannot be opened is retried in the background; see diagnostics().
        """
        for bus in self.buses.values():
            bus.start(receive_thread=not self.receive_in_loop)

    def start(self) -> None:
        """Open the buses and start the scheduler thread. Idempotent."""
        self.open()
        self.scheduler.start(final=self._send_final_frames)

    def tick(self, now_ns: int | None = None) -> int:
        """Run one scheduler cycle now (tests and manual stepping; not with start()).

        Returns:
            Number of frames handed to the buses.
        """
        return self.scheduler.tick(self._clock_ns() if now_ns is None else now_ns)

    def shutdown(self) -> None:
        """Send zero commands (and DISABLE to MIT motors), then close every bus. Idempotent."""
        if self._closed:
            return
        self._closed = True
        if self.scheduler.running:
            self.scheduler.stop()  # its final callback sends the zero frames
        else:
            self._send_final_frames()
        for bus in self.buses.values():
            bus.shutdown()

    def _send_final_frames(self) -> None:
        for a in self.actuators.values():
            a.shutdown()
        self.scheduler.tick(self._clock_ns())
        for a in self.actuators.values():
            send = self.buses[a.bus_name].send
            for msg in a.final_frames():
                send(msg)
        _log.info('CAN hardware: zero commands sent')

    def __enter__(self) -> CanHardware:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()

    # --- commands ---
    @property
    def joint_names(self) -> list[str]:
        """Joint names in config order."""
        return list(self.actuators)

    def set_command(
        self,
        name: str,
        mode: int,
        *,
        position: float = 0.0,
        velocity: float = 0.0,
        effort: float = 0.0,
        kp: float = 0.0,
        kd: float = 0.0,
        now_ns: int | None = None,
        age_ns: int = 0,
    ) -> None:
        """Set one joint's target (ActuatorCmd semantics, output shaft, SI).

        Args:
            name: joint name.
            mode: MODE_OFF/EFFORT/VELOCITY/POSITION/MIT (0..4).
            position: [rad].
            velocity: [rad/s].
            effort: [N·m].
            kp: [N·m/rad].
            kd: [N·m·s/rad].
            now_ns: receive time [ns]; default: the clock now.
            age_ns: how long before now_ns the command was issued [ns] (its stamp); the
                command timeout runs from then.

        Raises:
            CommandRejectedError: unknown joint, mode, NaN/inf field or negative gains;
                nothing reaches a motor and the previous target stays in force.
        """
        self._actuator(name).set_command(
            mode,
            (self._clock_ns() if now_ns is None else now_ns) - age_ns,
            position=position,
            velocity=velocity,
            effort=effort,
            kp=kp,
            kd=kd,
        )

    def set_target(
        self, name: str, target: JointTarget, *, now_ns: int | None = None, age_ns: int = 0
    ) -> None:
        """Set one joint's target, validated where it entered (``rm_base.joints``).

        The in-process path of the plugins and of the bridge's /actuator_cmd: the target
        is not checked again. Arguments as :meth:`set_command`.

        Raises:
            CommandRejectedError: unknown joint; nothing changes.
        """
        self._actuator(name).set_target(
            target, (self._clock_ns() if now_ns is None else now_ns) - age_ns
        )

    def _actuator(self, name: str) -> Actuator:
        actuator = self.actuators.get(name)
        if actuator is None:
            self._unknown_joint_commands += 1
            raise CommandRejectedError(f'unknown joint {name!r}; joints: {self.joint_names}')
        return actuator

    def add_power_limit(
        self, group: str, joints: Sequence[str], model: ChassisPowerModel
    ) -> PowerLimitStage:
        """Run one power limit over joints in the loop, after their update.

        See :mod:`rm_base.hardware.power_stage`; set the stage's ``limit_w`` to use it.

        Raises:
            HardwareConfigError: an unknown joint, or the group exists already.
        """
        unknown = [j for j in joints if j not in self.actuators]
        if unknown or not joints:
            raise HardwareConfigError(
                f'power limit {group!r}: unknown joint(s) {unknown}' if unknown
                else f'power limit {group!r}: no joints'
            )
        if group in self.power_limits:
            raise HardwareConfigError(f'power limit {group!r}: the group has one already')
        stage = PowerLimitStage(group, [self.actuators[j] for j in joints], model)
        if self.supercap is not None and self.supercap.config.group == group:
            stage.supercap = self.supercap
        self.scheduler.add_stage(stage)
        self.power_limits[group] = stage
        return stage

    def remove_power_limit(self, group: str) -> None:
        """Take a power limit out of the loop (no-op if there is none)."""
        stage = self.power_limits.pop(group, None)
        if stage is not None:
            self.scheduler.remove_stage(stage.name)

    def set_zero(self, name: str, max_speed: float) -> float:
        """Make joint name's present position its zero (see ``Actuator.zero_here``).

        Only for a joint at rest that nothing drives: a zero moved under a position loop
        would make it jump to the old pose.

        Args:
            name: the joint.
            max_speed: fastest the joint may turn and still count as at rest [rad/s].

        Returns:
            The joint's new ``zero_offset`` [rad].

        Raises:
            CommandRejectedError: unknown joint, offline, driven, moving, or its family
                cannot keep a zero (the message says which).
        """
        actuator = self.actuators.get(name)
        if actuator is None:
            raise CommandRejectedError(f'unknown joint {name!r}')
        state = actuator.state()
        if not state.online:
            raise CommandRejectedError(f'{name} is offline: no position to take as zero')
        if actuator.hold_reason is HoldReason.NONE:
            raise CommandRejectedError(
                f'{name} is driven: make the plugin that drives it PASSIVE first'
            )
        if not abs(state.velocity) <= max_speed:
            raise CommandRejectedError(
                f'{name} is moving ({state.velocity:.3f} rad/s, at rest below '
                f'{max_speed:g}): hold it still'
            )
        return actuator.zero_here()

    def request_system_command(self, name: str, command: SystemCommand | int) -> None:
        """Send enable / disable / set-zero / clear-error to an MIT-mode motor next tick.

        Raises:
            CommandRejectedError: unknown joint or not an MIT-mode motor.
            ValueRangeError: the motor family has no such command (Cheetah: clear error).
        """
        actuator = self.actuators.get(name)
        if not isinstance(actuator, MitActuator):
            raise CommandRejectedError(f'{name!r} is not an MIT-mode motor joint')
        actuator.request_system_command(command)

    # --- state ---
    def states(self, stamp_ns: int | None = None) -> list[JointState]:
        """State of every joint (config order), ActuatorState fields.

        stamp_ns: every state's stamp [ns]; default the receive time of its feedback.
        """
        return [a.state(stamp_ns) for a in self.actuators.values()]

    def links(self) -> dict[str, LinkReport]:
        """The kernel's report of each SocketCAN bus, by bus name.

        From `ip -details -statistics link`; a bus whose report could not be read is left
        out.
        """
        reports = {}
        for name, bus in self.buses.items():
            if bus.config.interface == 'socketcan':
                report = self._links.report(str(bus.config.channel))
                if report is not None:
                    reports[name] = report
        return reports

    def diagnostics(self) -> dict[str, Any]:
        """Bus counters and load, scheduler timing, and per-joint counters."""
        return {
            'buses': {name: bus.stats() for name, bus in self.buses.items()},
            'links': self.links(),
            'scheduler': self.scheduler.stats(),
            'joints': {name: a.diagnostics() for name, a in self.actuators.items()},
            'unknown_joint_commands': self._unknown_joint_commands,
            'supercap': (self.supercap.report(self._clock_ns())
                         if self.supercap is not None else None),
        }


class _FeedbackStage:
    """The loop's first stage with ``receive_in_loop``: every frame received so far."""

    name = 'feedback'
    reads: tuple[str, ...] = ()
    writes = (JOINT_STATES,)

    def __init__(self, buses: tuple[ManagedBus, ...]) -> None:
        self._buses = buses

    def __call__(self, now_ns: int, dt: float) -> bool:
        for bus in self._buses:
            bus.poll()
        return True
