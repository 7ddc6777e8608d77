"""CanBridgeNode: the thin rclpy edge over the CAN hardware layer (``can_bridge``).

Why one module: the node's set-up (simulator or hardware, publishers, services) and its
ROS edges; the work is in the modules it imports, its parameters in
:mod:`rm_base.bridge.node_params`.
"""

from __future__ import annotations

import functools
import threading
import time
from typing import Any

import can
from diagnostic_msgs.msg import DiagnosticArray
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from rm_base import motors as motor_families
from rm_base.bridge.command_input import ActuatorCmdInput
from rm_base.bridge.diagnostics import CommandStats, DiagnosticsReporter, SimulatorReporter
from rm_base.bridge.errors import BridgeConfigError, PowerLimitRejectedError
from rm_base.bridge.frames import FrameTap
from rm_base.bridge.live_gains import LiveGains
from rm_base.bridge.messages import (
    actuator_state_msg,
    can_frame_msg,
    joint_state_msg,
    state_msgs,
    time_msg,
)
from rm_base.bridge.node_params import declare_live_gains, read_parameters
from rm_base.bridge.params import SIM_CAN_DEFAULT, with_sim_world
from rm_base.bridge.power_limits import RemotePowerLimits, parse_power_limit
from rm_base.bridge.sim_config import world_config
from rm_base.bridge.sim_remote import SimRemoteInput
from rm_base.bridge.sim_services import SimFaultServices
from rm_base.config.calibration import CalibrationError
from rm_base.config.schema import InvalidValueError
from rm_base.hardware import CanHardware
from rm_base.hardware.bus import BusFactory
from rm_base.hardware.errors import CommandRejectedError, ValueRangeError
from rm_base.loop.data import JOINT_STATES, JOINT_TARGETS
from rm_base.plugin.inbox import Inbox
from rm_base.plugin.inbox_status import InboxReport
from rm_base.plugin.remote_power import POWER_LIMIT_QOS, POWER_LIMIT_TOPIC
from rm_base.ros.double_parameters import integers_as_doubles
from rm_base.ros.log import FastLogger
from rm_base.ros.node_main import inbox_node
from rm_base.ros.publish import publish
from rm_base.runtime import compiled
from rm_base.sim import SimConfigError, SimWorld, Timing
from rm_base.sim.bus_peer import BusPeer
from rm_msgs.msg import ActuatorCmd, ActuatorState, CanFrame, PowerLimit

NODE_NAME = 'can_bridge'

# The states go out from a plain thread woken after the loop's ticks, not from an executor
# timer: cheaper, and never behind callbacks (docs/PERFORMANCE.md, "States from a plain
# thread, not an executor timer").

# /actuator_cmd: reliable, as the plugins publish it; rm_robot waits for reliable readers
# to acknowledge its final zero command on shutdown.
_COMMAND_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
_STATE_QOS_DEPTH = 10
# ~/frames is a debug stream: a deeper history so a slow reader loses fewer frames.
_FRAMES_QOS_DEPTH = 1000
# Shortest time between two log lines about rejected commands (or dropped frames) [s].
_REJECT_LOG_PERIOD = 1.0

# The state publisher waits this long for the end of a loop tick before publishing anyway.
_TICK_WAIT_S = 0.005
# With nobody subscribed to the states, how often to look for a subscriber again [ns].
_UNHEARD_CHECK_NS = 50_000_000


class CanBridgeNode(Node):
    """can_bridge: runs the CAN hardware layer and puts it on ROS.

    - Reads ``buses.*``, ``joints.*``, ``scheduler.rate_hz`` and ``safety.*`` (exactly the
      hardware config schema, see :mod:`rm_base.bridge.params`) and builds a
      :class:`~rm_base.hardware.CanHardware`, whose own scheduler thread runs the 1 kHz
      loop (update all, pack all, send) and enforces every safety rule.
    - Subscribes ``actuator_cmd`` (rm_msgs/ActuatorCmd, reliable): each well-formed
      message is applied whole; a malformed or stale one (stamp older than the command
      timeout), or one computed from states older than this bridge's first (another
      bridge's, before a restart), is rejected whole, counted per reason and logged at
      most once a second per call site (:mod:`rm_base.bridge.commands`).
    - Publishes ``joint_states`` (sensor_msgs/JointState, output shaft, SI) and
      ``actuator_states`` (rm_msgs/ActuatorState) at ``publish_rate``, ``/diagnostics``
      at ``diagnostics_rate`` (:mod:`rm_base.bridge.diagnostics`), and with
      ``publish_frames`` every frame on ``~/frames`` (rm_msgs/CanFrame).
    - With ``sim: true`` every bus runs on ``rm_sim`` in one world built from the
      parameters (:mod:`rm_base.bridge.sim_config`) — with ``sim.can: socketcan`` the
      buses stay on the kernel's interfaces and the simulated motors answer there
      (:mod:`rm_base.sim.bus_peer`) — and std_srvs/SetBool services inject
      (``data: true``) or clear (``false``) faults: ``~/sim/<joint>/offline``, ``.../jam``,
      ``.../over_temperature``, ``.../garbage`` and ``~/sim/<bus>/bus_off``.
    - Every parameter is read once at start-up; ``ros2 param set`` is refused.
    - :meth:`shutdown` (also run by ``destroy_node``) sends zero output (and DISABLE to
      MIT motors) before the buses close.

    Args:
        **kwargs: passed to ``rclpy.node.Node`` (``context``, ``parameter_overrides``...).

    Raises:
        ConfigError: a parameter is missing, unknown or invalid; the message names it.
        BusError: a CAN log file cannot be opened.
    """

    def get_logger(self) -> FastLogger:
        """The node's logger, cheap enough for the 1 kHz loop thread (ros_logging)."""
        return self._fast_logger

    def __init__(self, **kwargs: Any) -> None:
        # Bus and joint names are the robot config's own, so the parameters under buses.*
        # and joints.* cannot be declared one by one in advance.
        super().__init__(NODE_NAME, automatically_declare_parameters_from_overrides=True, **kwargs)
        self._fast_logger = FastLogger(super().get_logger())
        self.hardware: CanHardware | None = None
        self.sim_world: SimWorld | None = None
        self.sim_peer: BusPeer | None = None
        self._frame_tap: FrameTap | None = None
        self._shut_down = False
        self._stop = threading.Event()
        self._publisher_thread: threading.Thread | None = None
        self._tick_done = threading.Event()
        self._inbox: Inbox | None = None
        self._commands: ActuatorCmdInput | None = None
        self._frames_dropped_reported = 0
        self.states_unheard = 0  # state publications skipped: nobody subscribed
        try:
            self._setup()
        except BaseException:
            self.destroy_node()
            raise

    # --- set-up ------------------------------------------------------------------------
    def _setup(self) -> None:
        settings, self._calibration = read_parameters(self)
        self.settings = settings
        hardware = dict(settings.hardware)
        if settings.sim is not None:
            try:
                self.sim_world = SimWorld.from_config(
                    world_config(settings.hardware_config, settings.sim)
                )
            except SimConfigError as err:
                raise BridgeConfigError(
                    f'simulated world (sim.*, joints.<joint>.sim.*): {err}'
                ) from err
            hardware = with_sim_world(hardware, self.sim_world)
        bus_factory: BusFactory = can.Bus
        if self.sim_world is not None and settings.sim is not None \
                and settings.sim.can != SIM_CAN_DEFAULT:
            # the simulated motors on the kernel's (or another python-can) interfaces,
            # joined before the robot's buses open so that no frame of theirs is missed
            try:
                self.sim_peer = BusPeer.open(
                    self.sim_world, settings.sim.can,
                    stepped=self.sim_world.timing is Timing.STEPPED,
                )
            except can.CanError as err:
                raise BridgeConfigError(f'sim.can: {err}') from err
            self.sim_peer.start()
            if self.sim_world.timing is Timing.REALTIME:
                self.sim_world.start()
        if settings.publish_frames:
            names = {(b.interface, str(b.channel)): b.name for b in settings.hardware_config.buses}
            self._frame_tap = FrameTap(names, bus_factory)
            bus_factory = self._frame_tap.factory
        world = self.sim_world
        self.stepped = world is not None and world.timing is Timing.STEPPED
        if world is not None and self.stepped:
            # Lockstep: the loop runs only in step(), on the world's clock, and takes the
            # feedback itself, so every tick is the same on every run.
            self.hardware = hw = CanHardware(
                hardware, bus_factory=bus_factory, clock_ns=lambda: world.time_ns,
                receive_in_loop=True, families=motor_families,
            )
        else:
            self.hardware = hw = CanHardware(
                hardware, bus_factory=bus_factory, families=motor_families,
            )
        self._joints = frozenset(hw.joint_names)
        self._commands = commands = ActuatorCmdInput(
            hw, self._joints, settings.hardware_config.safety.command_timeout_s,
            lambda: self.get_clock().now().nanoseconds,
            self._warn_rejected,
        )
        self._diagnostics = DiagnosticsReporter(
            NODE_NAME,
            {j.name: f'{j.bus} {j.type} id {j.id}' for j in settings.hardware_config.joints},
        )

        self._joint_states_pub = self.create_publisher(JointState, 'joint_states', _STATE_QOS_DEPTH)
        self._actuator_states_pub = self.create_publisher(
            ActuatorState, 'actuator_states', _STATE_QOS_DEPTH
        )
        self._diagnostics_pub = self.create_publisher(
            DiagnosticArray, '/diagnostics', _STATE_QOS_DEPTH
        )
        self._frames_pub = (
            self.create_publisher(CanFrame, '~/frames', _FRAMES_QOS_DEPTH)
            if settings.publish_frames
            else None
        )
        if self.stepped:  # lockstep: the test's executor delivers, in its own order
            self._inbox = None
            self._command_sub = self.create_subscription(
                ActuatorCmd, 'actuator_cmd', commands, _COMMAND_QOS
            )
        else:  # the loop hands /actuator_cmd out at the start of each tick (no executor hop)
            self._inbox = Inbox(
                inbox_node(self), self.get_clock(), name='actuator_cmd', writes=(JOINT_TARGETS,)
            )
            self._inbox.subscribe(
                ActuatorCmd, self.resolve_topic_name('actuator_cmd'),
                lambda msg, _receive_ns: commands(msg), _COMMAND_QOS,
            )
            hw.scheduler.add_stage(self._inbox)
        self._inbox_report = InboxReport(self.get_name())
        # joints.<joint>.<loop>.kp ... set while running, taken at the start of a tick
        loops = {
            joint.name: {'velocity_pid': joint.velocity_pid, 'position_pid': joint.position_pid}
            for joint in settings.hardware_config.joints
        }
        self._live_gains = LiveGains(hw.actuators, loops)
        declare_live_gains(self, loops)
        hw.scheduler.add_stage(self._live_gains)
        # rm_robot in a process of its own asks for its power stages here (rare: executor)
        self._power_limits = RemotePowerLimits(hw)
        self.power_limit_rejections = 0
        self._power_limit_sub = self.create_subscription(
            PowerLimit, POWER_LIMIT_TOPIC, self._on_power_limit, POWER_LIMIT_QOS
        )
        if self.sim_world is not None:
            self._sim_services = SimFaultServices(
                self, self.sim_world, self.hardware.joint_names,
                {b.name: str(b.channel) for b in settings.hardware_config.buses}, prefix='~/sim/',
            )
            if self.sim_world.remote is not None:
                self._sim_remote = SimRemoteInput(self, self.sim_world, prefix='~/sim/')
        self._zero_services = [
            self.create_service(
                Trigger, f'~/{joint}/set_zero', functools.partial(self._on_set_zero, joint)
            )
            for joint in sorted(self._joints)
        ]
        self.add_on_set_parameters_callback(self._on_set_parameters)
        # `kp 30` from ros2 param set or Foxglove: the double a file's `kp: 30` gives
        self.add_pre_set_parameters_callback(integers_as_doubles(self))

        if self.stepped:
            hw.open()
        else:
            hw.start()
        # the publisher thread: /actuator_states and /joint_states from the tick's feedback
        hw.scheduler.add_after_tick(self._tick_done.set, reads=(JOINT_STATES,))
        self._publisher_thread = threading.Thread(
            target=self._run_publisher, name='can_bridge-publish', daemon=True
        )
        self._publisher_thread.start()
        mode = 'on rm_sim' if self.sim_world is not None else 'on hardware'
        self.get_logger().info(
            f'{len(self._joints)} joint(s) on {len(hw.buses)} bus(es) {mode}, control at '
            f'{settings.hardware_config.rate_hz:g} Hz, states at {settings.publish_rate_hz:g} Hz'
            f', {_loop_build()}'
        )

    def _on_set_zero(
        self, joint: str, request: Trigger.Request, response: Trigger.Response
    ) -> Trigger.Response:
        response.success, response.message = self.set_zero(joint)
        return response

    def set_zero(self, joint: str) -> tuple[bool, str]:
        """~/<joint>/set_zero: make the joint's present position its zero, and keep it.

        Returns:
            Whether it was done, and what was done or why not.
        """
        assert self.hardware is not None
        try:
            zero = self.hardware.set_zero(joint, self.settings.calibration_max_speed)
        except (CommandRejectedError, ValueRangeError) as err:
            self.get_logger().warning(f'set_zero refused: {err}')
            return False, f'refused: {err}'
        kept = 'until the node stops (no calibration.file)'
        if self._calibration is not None:
            try:
                self._calibration.write('joints', joint, {'zero_offset': zero})
            except CalibrationError as err:
                kept = f'until the node stops: {err}'
            else:
                kept = f'saved to {self._calibration.path}'
        message = (
            f'{joint}: zero set at the present position (zero_offset {zero:.6f} rad), {kept}'
        )
        self.get_logger().info(message)
        return True, message

    # --- callbacks -----------------------------------------------------------------------
    def _warn_rejected(self, text: str) -> None:
        self.get_logger().warning(text, throttle_duration_sec=_REJECT_LOG_PERIOD)

    def _on_power_limit(self, msg: PowerLimit) -> None:
        try:
            self._power_limits.apply(parse_power_limit(msg, self._joints))
        except PowerLimitRejectedError as err:
            self.power_limit_rejections += 1
            self.get_logger().warning(
                f'rejected /power_limit ({self.power_limit_rejections} so far): {err}',
                throttle_duration_sec=_REJECT_LOG_PERIOD,
            )

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """``ros2 param set``: a joint's loop gains live (all of a call or none); else refused."""
        fixed = [p.name for p in parameters
                 if not LiveGains.takes(p.name) and p.name != 'use_sim_time']
        if fixed:
            return SetParametersResult(
                successful=False,
                reason=f'{", ".join(fixed)}: read at start-up: a change needs a restart '
                f'(live: joints.<joint>.velocity_pid.* and position_pid.*)',
            )
        try:
            self._live_gains.propose({p.name: p.value for p in parameters
                                      if LiveGains.takes(p.name)})
        except InvalidValueError as err:
            return SetParametersResult(successful=False, reason=str(err))
        self.get_logger().info(
            'set ' + ', '.join(f'{p.name} = {p.value!r}' for p in parameters)
            + ' (from the next tick on)'
        )
        return SetParametersResult(successful=True)

    # --- lockstep ---------------------------------------------------------------------------
    def step(self, ticks: int = 1) -> None:
        """Advance the stepped simulator and the control loop together, tick by tick.

        Each tick: the world moves one period (motors answer), then one loop tick runs at
        the world's new time (feedback, due plugins, update, pack, send).

        Raises:
            BridgeConfigError: the bridge does not run a stepped simulator
                (``sim.timing: stepped``), or its period differs from the loop's.
        """
        world, hw = self.sim_world, self.hardware
        if not self.stepped or world is None or hw is None:
            raise BridgeConfigError('step() needs sim: true and sim.timing: stepped')
        if world.period_ns != hw.scheduler.period_ns:
            raise BridgeConfigError(
                f'the simulator ticks every {world.period_ns} ns and the loop every '
                f'{hw.scheduler.period_ns} ns; lockstep needs the same period'
            )
        peer = self.sim_peer
        if peer is None:
            for _ in range(ticks):
                world.step(1)
                hw.tick(world.time_ns)
            return
        # over a kernel interface: each half tick's frames in every socket before the next
        channels = {name: str(bus.config.channel) for name, bus in hw.buses.items()}
        for _ in range(ticks):
            world.step(1)
            peer.settle({channels[n]: bus.frames_sent for n, bus in hw.buses.items()})
            hw.tick(world.time_ns)
            peer.settle({channels[n]: bus.frames_sent for n, bus in hw.buses.items()})

    # --- publishing (own thread) -----------------------------------------------------------
    def command_stats(self) -> CommandStats:
        """Counters of the /actuator_cmd input."""
        assert self._commands is not None
        return self._commands.stats()

    def publish_states(self) -> None:
        """Publish joint_states and actuator_states once (the publisher thread's job).

        A topic nobody subscribes is not built (the one-process robot's plugins read the
        joints in-process); the first subscriber gets the next period's message.
        """
        assert self.hardware is not None
        joints = self._joint_states_pub.get_subscription_count() > 0
        actuators = self._actuator_states_pub.get_subscription_count() > 0
        if not (joints or actuators):
            self.states_unheard += 1
            return
        states = self.hardware.states()
        now = self.get_clock().now()
        assert self._commands is not None
        self._commands.states_published(now.nanoseconds)
        stamp = now.to_msg()
        if joints and actuators:
            joint_states, actuator_states = state_msgs(states, stamp)
            publish(self._joint_states_pub, joint_states)
            publish(self._actuator_states_pub, actuator_states)
        elif joints:
            publish(self._joint_states_pub, joint_state_msg(states, stamp))
        else:  # rm_robot in a process of its own hears only /actuator_states
            publish(self._actuator_states_pub, actuator_state_msg(states, stamp))

    def _states_heard(self) -> bool:
        return (
            self._joint_states_pub.get_subscription_count() > 0
            or self._actuator_states_pub.get_subscription_count() > 0
        )

    def publish_diagnostics(self) -> None:
        """Publish /diagnostics once (the publisher thread's job)."""
        publish(self._diagnostics_pub, self.diagnostics_message())

    def diagnostics_message(self) -> DiagnosticArray:
        """What /diagnostics says now."""
        assert self.hardware is not None
        world = self.sim_world
        msg = self._diagnostics.build(
            self.hardware.diagnostics(),
            self.hardware.states(),
            self.command_stats(),
            self.get_clock().now().to_msg(),
            SimulatorReporter.stats(world)
            if world is not None and world.timing is Timing.REALTIME else None,
        )
        inbox = self._inbox
        if inbox is not None:  # /actuator_cmd taken and dropped
            msg.status.append(self._inbox_report.status(inbox))
        return msg

    def publish_frames(self) -> None:
        """Publish the frames seen since the last call on ~/frames."""
        tap = self._frame_tap
        if tap is None or self._frames_pub is None:
            return
        for frame in tap.drain():
            publish(
                self._frames_pub,
                can_frame_msg(frame.bus, frame.frame, frame.is_rx, time_msg(frame.stamp_ns)),
            )
        if tap.dropped != self._frames_dropped_reported:
            self._frames_dropped_reported = tap.dropped
            self.get_logger().warning(
                f'~/frames fell behind: {tap.dropped} frame(s) dropped so far',
                throttle_duration_sec=_REJECT_LOG_PERIOD,
            )

    def _run_publisher(self) -> None:
        state_period = round(1e9 / self.settings.publish_rate_hz)
        diag_period = round(1e9 / self.settings.diagnostics_rate_hz)
        next_state = next_diag = time.perf_counter_ns()
        errors = 0
        while not self._stop.is_set():
            wait_ns = min(next_state, next_diag) - time.perf_counter_ns()
            if wait_ns > 0 and self._stop.wait(wait_ns / 1e9):
                break
            now = time.perf_counter_ns()
            if now >= next_state and self._frame_tap is None and not self._states_heard():
                # nothing to build, no tick to wait for; look again for a subscriber soon
                self.states_unheard += 1
                next_state = max(next_state + state_period, now + _UNHEARD_CHECK_NS)
                if now < next_diag:
                    continue
            # Publish just after the loop's next tick, in its idle time, not in the middle
            # of a tick; a loop that does not tick delays the states by a short timeout.
            self._tick_done.clear()
            self._tick_done.wait(_TICK_WAIT_S)
            now = time.perf_counter_ns()
            try:
                if now >= next_state:
                    self.publish_states()
                    self.publish_frames()
                    # absolute deadlines; after a stall skip ahead instead of bursting
                    next_state = max(next_state + state_period, now)
                if now >= next_diag:
                    self.publish_diagnostics()
                    next_diag = max(next_diag + diag_period, now)
            except Exception as err:
                if self._stop.is_set() or not self.context.ok():
                    return
                errors += 1
                if errors == 1 or errors % 1000 == 0:
                    self.get_logger().error(f'publishing failed ({errors} so far): {err!r}')
                next_state = now + state_period
                next_diag = max(next_diag, now + state_period)

    # --- life cycle ---------------------------------------------------------------------------
    @property
    def edge_priority(self) -> int:
        """SCHED_FIFO priority for the process's threads other than the loop (0: normal)."""
        return self.settings.edge_priority

    @property
    def cpu_index(self) -> int | None:
        """The CPU (an index into the allowed ones) for every thread; None: no pinning."""
        return self.settings.cpu_index

    @property
    def cpu_latency_us(self) -> int | None:
        """The wake-up latency to ask of idle CPUs [µs]; None: no request."""
        return self.settings.cpu_latency_us

    def shutdown(self) -> None:
        """Stop publishing, send zero output (DISABLE to MIT motors), close. Idempotent."""
        if self._shut_down:
            return
        self._shut_down = True
        self._stop.set()
        if self._publisher_thread is not None:
            self._publisher_thread.join(timeout=5.0)
        if self.hardware is not None:
            self.hardware.shutdown()  # zero frames first, then the buses close
            try:
                # last word to the plugins: every joint MODE_OFF, command 0
                self.publish_states()
            except Exception as err:  # the context may already be gone
                self.get_logger().debug(f'final states not published: {err!r}')
        if self.sim_peer is not None:
            self.sim_peer.stop()
        if self.sim_world is not None:
            self.sim_world.close()

    def destroy_node(self) -> None:
        """Shut the hardware down (zero output first), then destroy the node."""
        self.shutdown()
        if self._inbox is not None:
            self._inbox.destroy()
            self._inbox = None
        super().destroy_node()


def _loop_build() -> str:
    """How the loop's modules run: compiled, or from source and why (runtime/compiled.py)."""
    reason = compiled.choose()
    if reason is None:
        return f'loop compiled ({len(compiled.MODULES)} modules)'
    return f'loop from source ({reason})'
