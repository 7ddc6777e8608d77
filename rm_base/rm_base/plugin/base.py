"""PluginBase: the API every rm_ros2 mechanism plugin implements.

Why one module: it is the whole plugin API in one class (lifecycle, state machine, watchdog,
joint I/O), which a plugin author reads in one place.

The base class owns the public methods (``init``, ``run``, ``enable``, ``disable``,
``reset``): checks, logging, the state machine, the command watchdog and zero output. A
plugin overrides hooks, all of which succeed by default:

- ``on_init()``: declare parameters (``self.params``), claim joints, subscribe commands,
  create its own publishers.
- ``update(now, dt)``: one tick: read commands and joint states, decide the state with
  ``transition()`` (a no-op when unchanged, so call it every tick), send joint targets.
- ``on_reset()``: clear integrators, ramps, filters (called on enable, disable, and when a
  watched command is lost).
- ``on_enable()`` / ``on_disable()``: anything else to do at those moments.
- ``on_command_lost(now, dt)``: called instead of ``update`` while a watched command is
  missing; the default commands zero output (the safe/PASSIVE behaviour).

States are an Enum of ints (``State``), with a safe state (``SAFE_STATE``, by default the
member named PASSIVE). Every transition is logged and published as rm_msgs/PluginState on
``~/<plugin>/state``.

Example:
    >>> class Spinner(PluginBase):
    ...     def on_init(self):
    ...         self.speed = self.params.double('speed', 1.0, description='speed', unit='rad/s')
    ...         self.joints = self.claim_joints(['spin_joint'])
    ...         self.cmd = self.subscribe_command('spin_cmd', Twist)
    ...
    ...     def update(self, now, dt):
    ...         self.transition(DefaultState.ACTIVE, 'spinning')
    ...         self.send_joint_targets({'spin_joint': JointTarget.with_velocity(self.speed)})
"""

from __future__ import annotations

import math
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from enum import Enum
from typing import Any, ClassVar, TypeVar

from rclpy.qos import DurabilityPolicy, QoSProfile, qos_profile_sensor_data
from rclpy.time import Time
from tf2_msgs.msg import TFMessage

from rm_base.config import schema
from rm_base.config.schema import InvalidValueError
from rm_base.errors import ConfigError
from rm_base.geometry.frame_tree import FrameTree
from rm_base.joints import JointTarget
from rm_base.loop.data import port
from rm_base.plugin.commands import CommandInput
from rm_base.plugin.errors import PluginConfigError, PluginInitError, TargetRejectedError
from rm_base.plugin.frames import TF_QOS, TF_STATIC_QOS, FramePublisher
from rm_base.plugin.joints import JointStates, JointStateView
from rm_base.plugin.node_io import DdsJointIO, NodeIO
from rm_base.plugin.outbox import is_heard, publish_built
from rm_base.plugin.params import PluginParams
from rm_base.plugin.state_machine import DefaultState, StateMachine, Transition
from rm_base.ros.log import FastLogger
from rm_msgs.msg import PluginState

_NS_PER_S = 1_000_000_000
_UNLIMITED = (-math.inf, math.inf)

# Latched: a tool or test that subscribes late still gets the current state at once.
STATE_QOS = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)

# Methods the framework owns; a plugin overrides the on_* / update hooks instead.
_FRAMEWORK_METHODS = ('init', 'run', 'enable', 'disable', 'reset', 'transition', 'zero_output')

_ERROR_LOG_PERIOD_NS = _NS_PER_S
T = TypeVar('T')


class PluginBase:
    """Base class of every plugin hosted by rm_robot.

    Class attributes a plugin may set:
        State: IntEnum of its states (values 0..255); default ``DefaultState``.
        SAFE_STATE: member of State to fall back to; default ``State.PASSIVE``.
        TRANSITIONS: optional table ``{state: states reachable from it}`` (see
            ``StateMachine``); going to SAFE_STATE is always allowed.

    Attributes available from ``on_init`` on:
        node: the host node (for the plugin's own publishers).
        name: instance name from the robot config, e.g. ``chassis``.
        type_name: plugin type, e.g. ``rm_plugins/StandChassis``.
        params: typed parameters under ``<name>.`` (see ``PluginParams``).
        logger: a child logger named after the instance.
        rate: configured run rate [Hz]; period = 1 / rate [s].
        command_timeout: default timeout of command inputs [s].

    The host calls ``run``, ``enable`` and ``disable`` one at a time (under a lock per
    plugin; the loop only tries it and runs the plugin at a later tick when it is held);
    subscription callbacks only touch the thread-safe command inputs and the joint-state
    view.
    """

    State: ClassVar[type[Enum]] = DefaultState
    SAFE_STATE: ClassVar[Enum | None] = None
    TRANSITIONS: ClassVar[Mapping[Any, Iterable[Any]] | None] = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        overridden = [m for m in _FRAMEWORK_METHODS if m in cls.__dict__]
        if overridden:
            raise TypeError(
                f'{cls.__name__} overrides PluginBase.{overridden[0]}(), which the framework '
                'owns; override the hooks on_init/update/on_reset/on_enable/on_disable/'
                'on_command_lost instead'
            )
        _check_states(cls)

    def __init__(self) -> None:
        self.node: Any = None
        self.name = ''
        self.type_name = ''
        self._params: PluginParams | None = None
        self.logger: Any = None
        self.rate = 0.0
        self.command_timeout = 0.0
        self.error_count = 0
        self._io: NodeIO | None = None
        self.loop_reads: tuple[str, ...] = ()  # its devices' data the loop reads for it
        self.config: Any = None  # what on_config keeps: the plugin's parameter set
        self._config: Any = None  # its declared parameter set (read_config), if it has one
        self._pending_config: Any = None  # set live, taken at the start of the next run
        self._machine: StateMachine[Any] | None = None
        self._state_pub: Any = None
        self._inputs: list[CommandInput[Any]] = []
        # Called (from the executor thread) when a command input stores a new command and
        # run_on_command is set: the host's loop runs the plugin at its next tick.
        self.command_listener: Callable[[], None] | None = None
        self._joints: tuple[str, ...] = ()
        self._joint_limits: dict[str, tuple[float, float]] = {}
        self._enabled = False
        self._lost_reason: str | None = None
        self._last_run_ns: int | None = None
        self._tick_now: Time | None = None  # the now of the run() in progress
        self._tick_states: JointStates | None = None  # the joint states it started with
        self._next_error_log_ns = 0
        self._suppressed_errors = 0

    # -- framework: lifecycle -----------------------------------------------------------

    def init(
        self,
        node: Any,
        name: str,
        params: PluginParams | None = None,
        io: NodeIO | None = None,
    ) -> None:
        """Set the plugin up on node as instance name; call ``on_init``.

        Declares ``<name>.rate`` [Hz] (default 100) and ``<name>.command_timeout`` [s]
        (default 0.1). The plugin starts disabled, in its safe state.

        Args:
            node: the host node.
            name: instance name; also the parameter prefix and the state topic.
            params: parameter access; default ``PluginParams(node, name, <class name>)``.
            io: the I/O the node's plugins share (the host's); default: joint I/O over
                DDS of this plugin's own.

        Raises:
            PluginConfigError: a parameter is missing or invalid, a joint is taken, or the
                plugin failed to initialise; the message names the plugin.
        """
        if self.node is not None:
            raise RuntimeError(f"plugin '{self.name}' is already initialised")
        params = params if params is not None else PluginParams(node, name, type(self).__name__)
        self.node, self.name, self._params = node, name, params
        self.type_name = params.plugin_type
        self.logger = FastLogger(node.get_logger()).get_child(name)
        try:
            self.rate = params.double(
                'rate', 100.0, description='rate at which run() is called', unit='Hz',
                gt=0.0, le=10000.0,
            )
            self.command_timeout = params.double(
                'command_timeout', 0.1,
                description='a command older than this is no command (watchdog)', unit='s',
                gt=0.0,
            )
            self.run_on_command = params.boolean(
                'run_on_command', True,
                description='also run at the next loop tick when a new command arrives, '
                'not only at the own rate (up to a period less latency)',
            )
            self._io = io if io is not None else DdsJointIO(node)
            safe = self.safe_state
            self._machine = StateMachine(
                self.State, safe, safe=safe, allowed=self.TRANSITIONS,
                listener=self._on_transition, initial_reason='loaded',
            )
            self._state_pub = self._nio.create_publisher(PluginState, f'~/{name}/state', STATE_QOS)
            self.on_init()
        except PluginConfigError as err:
            if not err.plugin:  # raised by the plugin's own code: say whose it is
                err.plugin = name
                err.args = (f'{self._where()}: {err}', *err.args[1:])
            raise
        except ConfigError as err:
            raise PluginInitError(f'{self._where()}: {err}', plugin=name) from err
        except Exception as err:
            raise PluginInitError(
                f'{self._where()}: init failed: {type(err).__name__}: {err}', plugin=name
            ) from err
        self.publish_state()

    def enable(self) -> bool:
        """Reset, then start acting on commands (safe state until update() decides).

        Returns:
            False if already enabled (nothing done).

        Raises:
            Exception: whatever on_enable raised; the plugin is left disabled then.
        """
        self._require_init()
        if self._enabled:
            return False
        self.reset()
        self._enabled = True
        try:
            self.on_enable()
        except Exception:
            self._enabled = False
            self.zero_output()
            raise
        if not self.transition(self.safe_state, 'enabled'):
            self.publish_state()  # same state and reason, but `enabled` changed
        return True

    def disable(self, reason: str = 'disabled') -> None:
        """Command zero output first, then stop, reset and go to the safe state.

        Safe to call in any state and more than once (each call publishes zero output).

        Args:
            reason: published as PluginState.reason.
        """
        self._require_init()
        self.zero_output()
        self._enabled = False
        self.reset()
        try:
            self.on_disable()
        except Exception as err:  # the joints are already off; report and go on
            self.logger.error(f'on_disable() failed: {type(err).__name__}: {err}')
        if not self.transition(self.safe_state, reason):
            self.publish_state()  # same state and reason, but `enabled` may have changed

    def reset(self) -> None:
        """Forget stale commands and timing, then call ``on_reset`` (integrators, ramps)."""
        for command in self._inputs:
            command.clear()
        self._lost_reason = None
        self._last_run_ns = None
        self.on_reset()

    def run(self, now: Time, dt: float | None = None) -> None:
        """One tick: the command watchdog, then ``update`` (or ``on_command_lost``).

        Never raises: an exception from a hook is logged (rate-limited), counted in
        ``error_count``, and the plugin's joints are commanded to zero output.

        Args:
            now: current time on the node's clock (rclpy Time).
            dt: time since the previous tick [s]; default from the previous ``now``, or the
                nominal period on the first tick after enable/reset or after the clock went
                back. With the default, a ``now`` equal to the previous one runs nothing.
        """
        if self._pending_config is not None:
            self._take_config()
        if not self._enabled:
            return
        now_ns = now.nanoseconds
        if dt is None:
            last = self._last_run_ns
            if last == now_ns:
                return  # the clock stood still (a node on /clock between two of its ticks)
            # a clock that went back (a replay started over) restarts the timing
            dt = (now_ns - last) / _NS_PER_S if last is not None and now_ns > last else (
                1.0 / self.rate)
        self._last_run_ns = now_ns
        self._tick_now = now
        # what this run's targets are computed from (a split bridge checks their stamp)
        self._tick_states = self._nio.joint_states.snapshot()
        try:
            reasons = [
                reason
                for command in self._inputs
                if command.watchdog and (reason := command.check(now_ns)) is not None
            ]
            if reasons:
                lost = '; '.join(reasons)
                if self._lost_reason is None:
                    # Falling back: nothing accumulated while commanded may carry over.
                    self._lost_reason = lost
                    self.on_reset()
                    self.transition(self.safe_state, lost)
                elif lost != self._lost_reason:  # a new kind of "no command" (rejected)
                    self._lost_reason = lost
                    self.transition(self.safe_state, lost)
                self.on_command_lost(now, dt)
            else:
                self._lost_reason = None
                self.update(now, dt)
        except Exception as err:
            self._on_run_error(err, now_ns)
        finally:
            self._tick_now = None
            self._tick_states = None

    # -- framework: state ---------------------------------------------------------------

    @property
    def enabled(self) -> bool:
        """Whether run() acts (set by enable/disable)."""
        return self._enabled

    @property
    def safe_state(self) -> Enum:
        """The state the plugin falls back to (SAFE_STATE or State.PASSIVE)."""
        return _safe_state_of(type(self))

    @property
    def state(self) -> Enum:
        """The current state."""
        machine = self._machine  # read several times a run: one lookup, not three calls
        if machine is None:
            raise self._not_initialised()
        state: Enum = machine.state
        return state

    @property
    def reason(self) -> str:
        """Why the last transition happened."""
        self._require_init()
        return self._sm.reason

    @property
    def joints(self) -> tuple[str, ...]:
        """Joints claimed by this plugin."""
        return self._joints

    @property
    def joint_states(self) -> JointStateView:
        """Latest state of every joint on /actuator_states (all joints, not only ours)."""
        self._require_init()
        return self._nio.joint_states

    def transition(self, new_state: Enum, reason: str) -> bool:
        """Go to new_state (a member of State) for reason; log and publish on change.

        Returns:
            True if the state or reason changed.

        Raises:
            TransitionError: TRANSITIONS does not allow it.
        """
        self._require_init()
        return self._sm.transition(new_state, reason)

    def state_message(self) -> PluginState:
        """Return the current state as rm_msgs/PluginState."""
        self._require_init()
        state, reason = self._sm.snapshot()
        msg = PluginState()
        msg.header.stamp = self.node.get_clock().now().to_msg()
        msg.plugin = self.name
        msg.type = self.type_name
        msg.enabled = self._enabled
        msg.state = int(state.value)
        msg.state_name = state.name
        msg.reason = reason
        msg.joints = list(self._joints)
        msg.joint_min = [self._joint_limits.get(j, _UNLIMITED)[0] for j in self._joints]
        msg.joint_max = [self._joint_limits.get(j, _UNLIMITED)[1] for j in self._joints]
        return msg

    def publish_state(self) -> None:
        """Publish the current state on ~/<name>/state."""
        self._state_pub.publish(self.state_message())

    # -- helpers for on_init / update ---------------------------------------------------

    @property
    def command_inputs(self) -> tuple[CommandInput[Any], ...]:
        """The command inputs this plugin subscribed (``subscribe_command``), in order."""
        return tuple(self._inputs)

    def subscribe_command(
        self,
        topic: str,
        msg_type: type,
        *,
        timeout: float | None = None,
        watchdog: bool = True,
        qos: Any = None,
        parse: Callable[[Any], Any] | None = None,
    ) -> CommandInput[Any]:
        """Subscribe to a command topic; return its input (``latest(now_ns)`` in update).

        The command's ``header.stamp`` starts its timeout (the receive time if the message
        has no header or a zero stamp). A stamp already older than the timeout is rejected
        as stale and logged; so is a message ``parse`` refuses. ``latest`` gives parse's
        record of the last valid command: the plugin checks nothing again.

        Args:
            topic: topic name (relative names follow the node's namespace).
            msg_type: message class, e.g. ``rm_msgs.msg.ChassisCmd``.
            timeout: validity of a command [s]; default ``<name>.command_timeout``.
            watchdog: while this input has no command, call ``on_command_lost`` (default:
                zero output) instead of ``update`` and go to the safe state with the reason.
            qos: subscription QoS; default best effort, depth 5 (matches any publisher).
            parse: message -> checked record, raising InputRejectedError with the reason
                (:class:`~rm_base.plugin.commands.CommandInput`); None: the message.
        """
        self._require_init()
        command: CommandInput[Any] = CommandInput(
            self.node.resolve_topic_name(topic),
            self.command_timeout if timeout is None else timeout,
            self.logger,
            watchdog=watchdog,
            parse=parse,
        )

        def on_command(msg: Any, receive_ns: int) -> None:
            if command.handle(msg, receive_ns) and self.run_on_command:
                listener = self.command_listener
                if listener is not None:
                    listener()

        qos = qos if qos is not None else qos_profile_sensor_data
        self._nio.subscribe_command(msg_type, command.topic, on_command, qos)
        self._inputs.append(command)
        return command

    def subscribe(
        self, topic: str, msg_type: type, callback: Callable[[Any, int], Any], qos: Any = None
    ) -> None:
        """Subscribe to a topic; ``callback(msg, receive_ns)`` must only store the message.

        Use this, not ``node.create_subscription``: hosted in the control loop, the loop
        hands the messages out at each tick (no executor in between), a topic another
        plugin of the robot publishes arrives in-process, and ``RobotHost.inject``
        (lockstep) reaches the same callback.

        Args:
            topic: topic name (relative names follow the node's namespace).
            msg_type: message class.
            callback: takes the message and its receive time on the node's clock [ns].
            qos: subscription QoS; default best effort, depth 5 (matches any publisher).
            parse: message -> checked record, raising InputRejectedError with the reason
                (:class:`~rm_base.plugin.commands.CommandInput`); None: the message.
        """
        self._require_init()
        qos = qos if qos is not None else qos_profile_sensor_data
        self._nio.subscribe(msg_type, self.node.resolve_topic_name(topic), callback, qos)

    def create_publisher(
        self, msg_type: type, topic: str, qos: Any, *, hand_over: bool = False
    ) -> Any:
        """Create a publisher for this plugin's own topics (states, odometry).

        Use this, not ``node.create_publisher``: hosted in the control loop, a plugin's
        messages are published by the ROS edge's thread, never by the loop itself.

        Args:
            msg_type: message class.
            topic: topic name (relative names follow the node's namespace).
            qos: QoS profile or history depth.
            hand_over: the plugin builds a new message for every publish and never
                changes it afterwards; the robot's other plugins then get that object,
                with no serialised copy. By default publish() takes a snapshot, so a
                plugin may refill one message object.
        """
        self._require_init()
        return self._nio.create_publisher(msg_type, topic, qos, hand_over)

    @property
    def in_loop(self) -> bool:
        """Whether a control loop runs this plugin (its after-tick callbacks get called)."""
        self._require_init()
        return self._nio.loop is not None

    def create_frame_publisher(self, *, static: bool = False) -> FramePublisher:
        """A sender of this plugin's transforms: into :attr:`frames`, and on /tf.

        static: /tf_static (latched), for transforms that never change (mounts); each
        send is then the whole set of them.
        """
        self._require_init()
        topic = '/tf_static' if static else '/tf'
        qos = TF_STATIC_QOS if static else TF_QOS
        publisher = self.create_publisher(TFMessage, topic, qos, hand_over=True)
        return FramePublisher(self._nio.frames, publisher, static=static)

    @property
    def frames(self) -> FrameTree:
        """The robot's frames as its plugins send them (``lookup(target, source)``)."""
        self._require_init()
        return self._nio.frames

    @staticmethod
    def heard(publisher: Any) -> bool:
        """Whether a message published now on publisher would reach anyone.

        A plugin builds a periodic report only then: nobody gets a message no plugin of
        the robot and no other node subscribes (the next one goes to the first subscriber).
        """
        return is_heard(publisher)

    @staticmethod
    def publish_built(publisher: Any, build: Callable[..., Any], *values: Any) -> None:
        """Publish ``build(*values)``; in the control loop, the ROS edge's thread builds it.

        For periodic reports: the loop then only keeps the values (which must not change
        after the call: numbers, strings, tuples), and build (a new message each call) and
        the serialisation run in the loop's idle time.
        """
        publish_built(publisher, build, *values)

    def loop_input(self, read: Callable[[], bool], name: str | None = None) -> bool:
        """Call read() at the start of every tick of the loop, before the plugins run.

        For a device the loop reads itself (a serial port): read() takes what waits,
        without blocking, hands it on, and returns whether there was anything. Its cost is
        then one of the loop's timed components (``name``, default ``<plugin> input``).

        Returns:
            False where no loop runs the plugins (then nothing will call it).
        """
        self._require_init()
        datum = port(self.name)
        if not self._nio.loop_input(name or f'{self.name} input', read, datum):
            return False
        self.loop_reads += (datum,)
        return True

    def power_limit(self, joints: Iterable[str], model: Any) -> Any:
        """A power limit over some of our joints, run in the control loop, or None.

        In the one-process robot the joints' velocity loops run at the loop rate and this
        stage scales their efforts by one factor after them (set its ``limit_w``; its
        ``last`` tells what it did); with rm_robot as a process of its own there is none,
        and the plugin limits the efforts it sends itself.

        Raises:
            TargetRejectedError: a joint is not ours.
        """
        self._require_init()
        joints = tuple(joints)
        foreign = [j for j in joints if j not in self._joints]
        if foreign:
            raise TargetRejectedError(
                f"plugin '{self.name}' does not drive joint(s) {', '.join(foreign)}"
            )
        return self._nio.power_limit(self.name, joints, model)

    def claim_joints(
        self, joints: Iterable[str], limits: Mapping[str, tuple[float, float]] | None = None
    ) -> tuple[str, ...]:
        """Declare the joints this plugin drives (zero output turns them off).

        May be called more than once; joints add up. limits: a joint's position range
        [rad] where the plugin keeps it (PluginState tells tools, e.g. ``rmcli tune``).

        Raises:
            JointClaimError: a joint is already driven by another plugin.
        """
        self._require_init()
        claimed = self._nio.claim(self.name, joints)
        self._joints = tuple(dict.fromkeys(self._joints + claimed))
        self._joint_limits.update(limits or {})
        return claimed

    def send_joint_targets(self, targets: Mapping[str, JointTarget]) -> None:
        """Send targets for some or all of our joints, as one coordinated set.

        In the one-process robot they are set on the actuators directly; with rm_robot
        as a process of its own they go out as one rm_msgs/ActuatorCmd stamped with the
        ``now`` of the tick in progress (outside ``run``, the node clock's now).

        Raises:
            TargetRejectedError: a joint is not ours, or a target has a NaN/inf field or
                a negative gain; nothing is sent then (``run`` turns the joints off for
                this tick).
        """
        self._require_init()
        foreign = [joint for joint in targets if joint not in self._joints]
        if foreign:
            raise TargetRejectedError(
                f"plugin '{self.name}' does not drive joint(s) {', '.join(foreign)} "
                f"(claimed: {', '.join(self._joints) or 'none'})"
            )
        self._send(targets)

    def zero_output(self) -> None:
        """Command MODE_OFF (zero output, limp) on every joint this plugin drives."""
        self._require_init()
        if self._joints:
            self._send(dict.fromkeys(self._joints, JointTarget.off()))

    # -- hooks ----------------------------------------------------------------------------

    def on_init(self) -> None:
        """Declare parameters, claim joints, subscribe commands. Default: nothing."""

    def update(self, now: Time, dt: float) -> None:
        """One tick while enabled and commanded. Default: nothing.

        Args:
            now: current time on the node's clock (rclpy Time; ``now.nanoseconds``).
            dt: time since the previous tick [s].
        """

    def on_reset(self) -> None:
        """Clear integrators, ramps, filters, remembered targets. Default: nothing."""

    def on_enable(self) -> None:
        """Called by enable() after reset. Default: nothing."""

    def on_disable(self) -> None:
        """Called by disable() after zero output and reset. Default: nothing."""

    def on_command_lost(self, now: Time, dt: float) -> None:
        """Each tick while a watched command is missing. Default: zero output."""
        self.zero_output()

    # -- internals ------------------------------------------------------------------------

    def _send(self, targets: Mapping[str, JointTarget]) -> None:
        # Within run() the tick's now, read once per tick: the targets are for that instant.
        now = self._tick_now
        if now is None:
            now = self.node.get_clock().now()
        self._nio.send(targets, now, self._tick_states)

    def _on_transition(self, change: Transition[Any]) -> None:
        if change.previous == change.current:
            self.logger.info(f'{change.current.name}: {change.reason}')
        else:
            self.logger.info(f'{change.previous.name} -> {change.current.name}: {change.reason}')
        if self._state_pub is not None:
            self._state_pub.publish(self.state_message())

    def _on_run_error(self, err: Exception, now_ns: int) -> None:
        self.error_count += 1
        try:
            self.zero_output()
            self._lost_reason = None
            self.on_reset()
            self.transition(self.safe_state, f'run failed: {type(err).__name__}: {err}')
        except Exception as inner:  # the joints must go off even if this fails too
            err = inner
        # First error with its traceback, later ones at most once a second.
        if self.error_count == 1:
            self.logger.error(
                f'run failed, joints off: {type(err).__name__}: {err}\n{traceback.format_exc()}'
            )
        elif time.monotonic_ns() >= self._next_error_log_ns:
            more = f' ({self._suppressed_errors} more)' if self._suppressed_errors else ''
            self.logger.error(f'run failed again, joints off: {type(err).__name__}: {err}{more}')
            self._suppressed_errors = 0
            self._next_error_log_ns = time.monotonic_ns() + _ERROR_LOG_PERIOD_NS
        else:
            self._suppressed_errors += 1

    def _require_init(self) -> None:
        if self._machine is None:
            raise self._not_initialised()

    def _not_initialised(self) -> RuntimeError:
        return RuntimeError(f'{type(self).__name__}: call init() first')

    # -- framework: parameters ------------------------------------------------------------

    def read_config(self, cls: type[T]) -> T:
        """Declare and read the plugin's parameter set cls (``<name>.<key>``); return it.

        cls is a dataclass of :func:`rm_base.config.schema.declare` fields. Its keys marked
        ``tunable`` may then be set while the plugin runs (``propose_config``): the new set
        reaches ``on_config`` at the start of a run, never in the middle of one.
        """
        config = self.params.read(cls)
        self._config = config
        return config

    def propose_config(self, changes: Mapping[str, object]) -> Any:
        """The parameter set with changes (``{key below <name>.: value}``), checked; not applied.

        Raises:
            InvalidValueError: a key that is read at start-up only, or a value its key
                refuses (the text starts with the key); ConfigError: values that do not fit
                together.
        """
        base = self._pending_config if self._pending_config is not None else self._config
        known = set() if base is None else {
            prefix + key.name for prefix, key in schema.keys(type(base))
        }
        for name in changes:
            if name not in known:
                raise InvalidValueError(f'{name} is read at start-up: a change needs a restart')
        return schema.with_values(base, changes)

    def set_config(self, config: Any) -> None:
        """Apply a set from ``propose_config`` at the start of the next run (any thread)."""
        self._pending_config = config

    def on_config(self, config: Any) -> None:
        """Hook: the parameter set changed (between runs); the default keeps it as config.

        Override to rebuild what the plugin derives from its parameters (calling this too
        when config is the whole set; a plugin whose set is only its live part merges it).
        """
        self.config = config

    def _take_config(self) -> None:
        config, self._pending_config = self._pending_config, None
        self._config = config
        self.on_config(config)

    @property
    def params(self) -> PluginParams:
        """The plugin's parameters (``<name>.<key>``); from ``init`` on."""
        if self._params is None:
            raise self._not_initialised()
        return self._params

    @property
    def _sm(self) -> StateMachine[Any]:
        self._require_init()
        assert self._machine is not None
        return self._machine

    @property
    def _nio(self) -> NodeIO:
        if self._io is None:
            raise self._not_initialised()
        return self._io

    def _where(self) -> str:
        return f"plugin '{self.name}'" + (f' ({self.type_name})' if self.type_name else '')


def _safe_state_of(cls: type[PluginBase]) -> Enum:
    if cls.SAFE_STATE is not None:
        return cls.SAFE_STATE
    return cls.State['PASSIVE']


def _check_states(cls: type[PluginBase]) -> None:
    states = cls.State
    if not (isinstance(states, type) and issubclass(states, Enum)) or not list(states):
        raise TypeError(f'{cls.__name__}.State must be a non-empty Enum')
    for member in states:
        if not isinstance(member.value, int) or not 0 <= member.value <= 255:
            raise TypeError(
                f'{cls.__name__}.State.{member.name} must have an int value in 0..255 '
                f'(PluginState.state is uint8), got {member.value!r}'
            )
    if cls.SAFE_STATE is None and 'PASSIVE' not in states.__members__:
        raise TypeError(f'{cls.__name__} needs SAFE_STATE or a State member named PASSIVE')
    if cls.SAFE_STATE is not None and not isinstance(cls.SAFE_STATE, states):
        raise TypeError(f'{cls.__name__}.SAFE_STATE must be a member of {states.__name__}')
