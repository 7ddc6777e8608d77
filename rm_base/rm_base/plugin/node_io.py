"""What all plugins on one node share: joint I/O, publishers and who drives which joint.

Why one module: the two kinds of joint I/O differ only in how targets leave and states
arrive; the claims, publishers, subscriptions and loop stages they share live in the base.

Joint I/O comes in two kinds, chosen by the host before any plugin is initialised:

- :class:`DdsJointIO` (``rm_robot`` as a process of its own): targets go out on
  /actuator_cmd and joint states come in on /actuator_states, to and from a can_bridge
  process.
- :class:`LocalJointIO` (the one-process robot): targets are set on the actuators
  directly and the view is filled from them by the control loop, with no DDS hop and no
  message in between (docs/ARCHITECTURE.md, "One loop").

A host may also give the I/O an :class:`~rm_base.plugin.outbox.Outbox`: then every
publisher a plugin creates through :meth:`NodeIO.create_publisher` hands its messages to
the outbox's thread, so the control loop never publishes itself; and an
:class:`~rm_base.plugin.inbox.Inbox`: then every subscription a plugin makes through
:meth:`NodeIO.subscribe` reaches its callback in the control loop, never through an executor.

The host creates one for its node and hands it to each plugin's ``init`` (a plugin
initialised on its own gets DDS joint I/O of its own). The plugin layer uses rclpy only
through the node object it is given (plus rclpy's QoS value types).
"""

from __future__ import annotations

import abc
import threading
from collections.abc import Callable, Iterable, Sequence
from typing import Any, Protocol

from rclpy.qos import qos_profile_sensor_data
from rclpy.serialization import deserialize_message
from rclpy.time import Time

from rm_base.control import ChassisPowerModel
from rm_base.geometry.frame_tree import FrameTree
from rm_base.joints import JointState, JointTarget
from rm_base.loop.data import JOINT_TARGETS, PUBLISHED
from rm_base.plugin.command_mux import CommandMux, CommandSource
from rm_base.plugin.errors import JointClaimError, TargetRejectedError
from rm_base.plugin.inbox import Inbox
from rm_base.plugin.joints import (
    JointStates,
    JointStateView,
    JointTargets,
    build_actuator_cmd,
    check_targets,
    oldest_stamp,
)
from rm_base.plugin.outbox import Outbox
from rm_base.plugin.remote_power import POWER_LIMIT_QOS, POWER_LIMIT_TOPIC, RemotePowerStage
from rm_msgs.msg import ActuatorCmd, ActuatorState, PowerLimit

ACTUATOR_CMD_TOPIC = 'actuator_cmd'
"""Joint targets to the CAN bridge (relative: follows the node's namespace)."""

ACTUATOR_STATES_TOPIC = 'actuator_states'
"""Joint states from the CAN bridge (relative: follows the node's namespace)."""

# Reliable, keep last 10: a reliable writer matches both reliable and best-effort readers,
# so the bridge may pick either.
ACTUATOR_CMD_QOS_DEPTH = 10

class JointBackend(Protocol):
    """The part of the CAN hardware layer that local joint I/O uses (CanHardware)."""

    def set_target(self, name: str, target: JointTarget) -> None:
        """Set one joint's target, already checked (output shaft, SI)."""

    def states(self, stamp_ns: int | None = None) -> list[JointState]:
        """Every joint's state, stamped stamp_ns (default: its feedback's receive time)."""

    def add_power_limit(self, group: str, joints: Sequence[str], model: Any) -> Any:
        """Run one power limit over joints at the loop rate; return its stage."""

    def remove_power_limit(self, group: str) -> None:
        """Take the power limit of group out of the loop."""


class _InputStage:
    """A plugin's device read as a loop stage (``Stage``): it writes the device's datum."""

    reads: tuple[str, ...] = ()

    def __init__(self, name: str, read: Callable[[], bool], datum: str) -> None:
        self.name = name
        self.writes = (datum,)
        self._read = read

    def __call__(self, now_ns: int, dt: float) -> bool:
        return self._read()


class NodeIO(abc.ABC):
    """Shared plugin I/O of one node; see the subclasses.

    Attributes:
        targets_datum: what a plugin that sets joint targets writes in the loop's order
            (rm_base.loop.data): the joint targets themselves, or what it publishes.
    """

    targets_datum = PUBLISHED

    def __init__(self, node: Any, joint_states: JointStateView) -> None:
        self.node = node
        self.joint_states = joint_states
        self.outbox: Outbox | None = None
        self.inbox: Inbox | None = None
        self.loop: Any = None  # the control loop running the plugins (a Scheduler)
        # arbitrates the plugins' command topics between commanders (None: none does)
        self.command_mux: CommandMux | None = None
        self._inputs: list[str] = []  # names of the plugins' input stages in the loop
        self.frames = FrameTree()  # the plugins' transforms (rm_base.plugin.frames)
        self._claims: dict[str, str] = {}
        self._lock = threading.Lock()
        self._handlers: dict[str, list[Callable[[Any, int], Any]]] = {}
        self._local: dict[str, int] = {}  # topic: publishers of this node's plugins

    @abc.abstractmethod
    def send(self, targets: JointTargets, now: Time, states: JointStates | None = None) -> None:
        """Apply one coordinated set of joint targets (all or none), stamped now.

        Args:
            targets: {joint: target}.
            now: the time they are for.
            states: the joint states they were computed from (the view at the start of
                the plugin's run); None: the view now.

        Raises:
            TargetRejectedError: a target is invalid (``check_targets``); nothing is sent.
        """

    def power_limit(self, group: str, joints: Sequence[str], model: Any) -> Any:
        """A power limit over joints, run after their loops, or None where none runs them.

        Local joint I/O puts it in this process's loop; over DDS the bridge runs it (it
        gets it on /power_limit).
        """
        return None

    def loop_input(self, name: str, read: Callable[[], bool], datum: str) -> bool:
        """Run read() in every tick, before the plugin reading datum; False if no loop.

        read() takes what a device holds without blocking and returns whether it took
        anything (the loop times it then, as the component ``name``).
        """
        if self.loop is None:
            return False
        self.loop.add_stage(_InputStage(name, read, datum))
        self._inputs.append(name)
        return True

    def release(self) -> None:
        """Take the plugins' input stages out of the loop. Idempotent."""
        while self._inputs:
            self.loop.remove_stage(self._inputs.pop())

    def create_publisher(
        self, msg_type: type, topic: str, qos: Any, hand_over: bool = False
    ) -> Any:
        """A publisher for a plugin: through the outbox if there is one.

        With an outbox its messages also reach this node's plugins directly (``deliver``),
        so the inbox stops taking that topic from DDS. ``hand_over``: see
        :meth:`Outbox.wrap <rm_base.plugin.outbox.Outbox.wrap>`.
        """
        publisher = self.node.create_publisher(msg_type, topic, qos)
        if self.outbox is None:
            return publisher
        name = publisher.topic_name
        with self._lock:
            self._local[name] = self._local.get(name, 0) + 1
        if self.inbox is not None:
            self.inbox.drop(name)
        return self.outbox.wrap(publisher, hand_over)

    def deliver(self, topic: str, data: Any, msg_type: type) -> int:
        """Hand a message this node publishes to its plugins on topic.

        The outbox's loopback: data is the serialised snapshot (one copy for all the
        topic's callbacks, none if there are none) or the message itself, handed over.
        Returns the number of callbacks that got it.
        """
        with self._lock:
            handlers = tuple(self._handlers.get(topic, ()))
        if not handlers:
            return 0
        msg = deserialize_message(data, msg_type) if isinstance(data, bytes) else data
        receive_ns = self.node.get_clock().now().nanoseconds
        for handler in handlers:
            handler(msg, receive_ns)
        return len(handlers)

    def listens(self, topic: str) -> bool:
        """Whether a plugin of this node subscribes topic (a resolved name)."""
        return bool(self._handlers.get(topic))

    def foreign_publishers(self) -> dict[str, int]:
        """Publishers the plugins do not hear, as {topic: count}.

        Those of other nodes on topics that this node's plugins both publish and
        subscribe: the plugins get such a topic in-process from their own publisher.
        """
        with self._lock:
            local = {t: n for t, n in self._local.items() if t in self._handlers}
        counts = {t: self.node.count_publishers(t) - n for t, n in local.items()}
        return {t: n for t, n in counts.items() if n > 0}

    def subscribe(
        self, msg_type: type, topic: str, callback: Callable[[Any, int], Any], qos: Any
    ) -> None:
        """Subscribe a plugin's callback(msg, receive_ns) to topic (a resolved name).

        Through the loop's inbox if there is one, else on the node (its executor calls
        back); ``inject`` reaches the callback either way.
        """
        if self.inbox is not None:
            self.inbox.subscribe(msg_type, topic, callback, qos)
        else:
            clock = self.node.get_clock()
            self.node.create_subscription(
                msg_type, topic, lambda msg: callback(msg, clock.now().nanoseconds), qos
            )
        self.add_handler(topic, callback)

    def subscribe_command(
        self, msg_type: type, topic: str, callback: Callable[[Any, int], Any], qos: Any
    ) -> None:
        """Subscribe a command topic (a resolved name), arbitrated if the node has a mux.

        Each command source's topic is subscribed; a message reaches callback only while its
        source is in charge of the topic (:mod:`rm_base.plugin.command_mux`).
        """
        mux = self.command_mux
        if mux is None:
            self.subscribe(msg_type, topic, callback, qos)
            return
        for source, source_topic in mux.add_topic(topic):
            def arbitrated(msg: Any, receive_ns: int, source: CommandSource = source) -> None:
                if mux.offer(topic, source, receive_ns):
                    callback(msg, receive_ns)

            self.subscribe(msg_type, source_topic, arbitrated, qos)

    def add_handler(self, topic: str, handler: Callable[[Any, int], Any]) -> None:
        """Record a plugin's subscription callback for topic (a resolved name).

        On a latched topic that a plugin of this node published on, the handler gets the
        last message at once, as a transient-local DDS subscriber would.
        """
        with self._lock:
            self._handlers.setdefault(topic, []).append(handler)
        last = self.outbox.last_latched(topic) if self.outbox is not None else None
        if last is not None:
            data, msg_type = last
            msg = deserialize_message(data, msg_type) if isinstance(data, bytes) else data
            handler(msg, self.node.get_clock().now().nanoseconds)

    def inject(self, topic: str, msg: Any) -> int:
        """Hand msg to every plugin callback of topic, as if it had arrived now.

        Args:
            topic: topic name (relative names follow the node's namespace).
            msg: the message, handed over as it is (callbacks only store it).

        Returns:
            Number of callbacks that got it.
        """
        with self._lock:
            handlers = tuple(self._handlers.get(self.node.resolve_topic_name(topic), ()))
        receive_ns = self.node.get_clock().now().nanoseconds
        for handler in handlers:
            handler(msg, receive_ns)
        return len(handlers)

    def claim(self, plugin: str, joints: Iterable[str]) -> tuple[str, ...]:
        """Record that plugin drives joints; return them as a tuple.

        Raises:
            JointClaimError: a joint is listed twice or already driven by another plugin.
        """
        names = tuple(joints)
        if len(set(names)) != len(names):
            duplicates = sorted({n for n in names if names.count(n) > 1})
            raise JointClaimError(
                f"plugin '{plugin}' lists joint(s) twice: {', '.join(duplicates)}", plugin=plugin
            )
        with self._lock:
            taken = {n: self._claims[n] for n in names if self._claims.get(n, plugin) != plugin}
            if taken:
                conflicts = ', '.join(
                    f"joint '{joint}' (already driven by plugin '{owner}')"
                    for joint, owner in taken.items()
                )
                raise JointClaimError(f"plugin '{plugin}' cannot drive {conflicts}", plugin=plugin)
            for name in names:
                self._claims[name] = plugin
        return names

    def claims(self) -> dict[str, str]:
        """Return {joint: plugin} for every claimed joint."""
        with self._lock:
            return dict(self._claims)


class DdsJointIO(NodeIO):
    """Joint targets on /actuator_cmd, joint states from /actuator_states."""

    def __init__(self, node: Any) -> None:
        super().__init__(node, JointStateView(node.get_logger()))
        self.actuator_cmd = node.create_publisher(
            ActuatorCmd, ACTUATOR_CMD_TOPIC, ACTUATOR_CMD_QOS_DEPTH
        )
        self._command_edge: tuple[Outbox, Any] | None = None  # (outbox, its wrapper)
        clock = node.get_clock()

        def on_actuator_states(msg: ActuatorState) -> None:
            self.joint_states.handle(msg, clock.now().nanoseconds)

        # Best effort matches a reliable or a best-effort bridge; an old state is worthless.
        self._subscription = node.create_subscription(
            ActuatorState, ACTUATOR_STATES_TOPIC, on_actuator_states, qos_profile_sensor_data
        )
        self._power_limit_pub: Any = None

    def send(self, targets: JointTargets, now: Time, states: JointStates | None = None) -> None:
        """Publish targets as one rm_msgs/ActuatorCmd stamped now.

        Its ``states_stamp`` is the oldest stamp of their joints' states, so a bridge
        restarted since refuses them (docs/RELIABILITY.md, "A restarted bridge").
        Through the host's outbox where it has one: the loop thread never hands a message
        to DDS, whose send can block while a node joins (docs/PERFORMANCE.md, "No DDS call
        from the loop").
        """
        msg = build_actuator_cmd(targets)
        msg.header.stamp = now.to_msg()
        used = self.joint_states.snapshot() if states is None else states
        msg.states_stamp.sec, msg.states_stamp.nanosec = divmod(
            oldest_stamp(used, targets), 1_000_000_000
        )
        self._command_publisher().publish(msg)

    def _command_publisher(self) -> Any:
        outbox = self.outbox
        if outbox is None:
            return self.actuator_cmd
        if self._command_edge is None or self._command_edge[0] is not outbox:
            # handed over: build_actuator_cmd makes a new message for every send
            self._command_edge = (outbox, outbox.wrap(self.actuator_cmd, hand_over=True))
        return self._command_edge[1]

    def power_limit(
        self, group: str, joints: Sequence[str], model: ChassisPowerModel
    ) -> RemotePowerStage:
        """A power limit the bridge runs in its loop, asked for on /power_limit."""
        if self._power_limit_pub is None:
            self._power_limit_pub = self.create_publisher(
                PowerLimit, POWER_LIMIT_TOPIC, POWER_LIMIT_QOS
            )
        return RemotePowerStage(self._power_limit_pub, group, joints, model, self.joint_states)


class LocalJointIO(NodeIO):
    """Joint targets set on the actuators directly; the loop refreshes the view."""

    targets_datum = JOINT_TARGETS

    def __init__(self, node: Any, hardware: JointBackend) -> None:
        super().__init__(node, JointStateView(node.get_logger()))
        self._hardware = hardware
        self._power_limits: list[str] = []

    def send(self, targets: JointTargets, now: Time, states: JointStates | None = None) -> None:
        """Set targets on the actuators (checked here, once; the hardware clock stamps them)."""
        set_target = self._hardware.set_target
        for joint, target in check_targets(targets):
            try:
                set_target(joint, target)
            except Exception as err:  # an unknown joint: checked targets are otherwise valid
                raise TargetRejectedError(f'joint {joint!r}: {err}') from err

    def power_limit(self, group: str, joints: Sequence[str], model: Any) -> Any:
        """The hardware's power limit stage over joints, run after their 1 kHz loops."""
        stage = self._hardware.add_power_limit(group, joints, model)
        self._power_limits.append(group)
        return stage

    def release(self) -> None:
        """Take the plugins' power limits and input stages out of the loop."""
        super().release()
        while self._power_limits:
            self._hardware.remove_power_limit(self._power_limits.pop())

    def refresh(self, stamp_ns: int) -> None:
        """Fill the view from the actuators (the loop, before plugins run).

        Args:
            stamp_ns: the tick's time on the plugins' clock [ns], the states' stamp.
        """
        self.joint_states.replace({s.name: s for s in self._hardware.states(stamp_ns)})
