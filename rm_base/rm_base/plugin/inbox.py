"""Inbox: the plugins' subscriptions, handed to the control loop each tick; the loop never takes.

A message an executor delivers costs the loop a thread switch and a wait for the GIL
behind the executor's thread (docs/PERFORMANCE.md). The inbox's subscriptions live on a
node that no executor spins (``rm_base.ros.node_main.inbox_node`` makes one beside the owner).
The inbox's own thread waits on them (rclpy's wait set, the GIL released while it waits),
takes what arrives (:class:`rm_base.ros.take.TakeBuffer`: the GIL released while rcl
takes), deserialises it and appends the message to the subscription's queue. The loop's
first stage, :meth:`Inbox.__call__`, stamps every queued message with the tick's receive
time and hands it to the plugin's callback, the same callback a subscription or
``inject`` runs, so a command reaches its plugin at the next tick. Deserialising is most
of a take's cost; done here, in the loop's sleep, it stays out of the tick: a tick's
commands stage costs a third of what it did, the process as much CPU as before
(docs/PERFORMANCE.md, "Commands arrive deserialised"). A message that does not
deserialise is counted in ``errors``, logged, and never queued.

The loop itself never takes from DDS: a take can wait a third of a second for Fast DDS's locks
when another node joins (docs/PERFORMANCE.md, "No DDS call from the loop"), and
then only this thread waits. Its priority is below the loop's and it runs on the loop's
CPU (``rm_base.runtime.realtime``), so it takes in the loop's sleep, never mid-tick.

A queue holds as many messages as the subscription's QoS depth, as DDS would: if the loop
falls behind, the oldest are dropped, counted per topic and logged. Messages DDS itself
dropped before this thread took them (its keep-last history overwritten in a flood) show
as gaps in each publisher's sequence numbers: counted per topic (``lost_by_topic``) and
logged too.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any, NamedTuple

from rclpy.exceptions import InvalidHandle
from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.qos import HistoryPolicy, QoSProfile
from rclpy.serialization import deserialize_message

from rm_base.loop.data import COMMANDS
from rm_base.plugin.commands import LogThrottle
from rm_base.ros.take import MessageInfo, SequenceGaps, TakeBuffer

_log = logging.getLogger(__name__)

#: Stage name in the loop's timing statistics.
STAGE_NAME = 'commands'
#: Queue length for a subscription that keeps all its messages (KEEP_ALL, depth 0).
MAX_QUEUED = 1000

# A failing callback, a drop or a failing take is logged at most this often [ns].
_LOG_PERIOD_NS = 1_000_000_000
# Longest one wait of the thread [ns]: it wakes for its guard condition anyway; this only
# bounds how long a shut-down context goes unnoticed.
_WAIT_TIMEOUT_NS = 500_000_000
# Pause after a failing wait or take before the thread tries again [s].
_RETRY_S = 0.1
# How long destroy waits for the thread [s]: a take can block a third of a second.
_JOIN_TIMEOUT_S = 2.0


def _never_called(msg: Any) -> None:  # the inbox takes the messages, no executor
    raise AssertionError('an executor spun the inbox node')


def queue_depth(qos: Any) -> int:
    """How many messages a subscription with this QoS (or history depth) keeps."""
    if isinstance(qos, int):
        return qos if qos > 0 else MAX_QUEUED
    if not isinstance(qos, QoSProfile):
        raise TypeError(f'QoS must be a QoSProfile or a depth, got {qos!r}')
    if qos.history == HistoryPolicy.KEEP_ALL or qos.depth <= 0:
        return MAX_QUEUED
    return int(qos.depth)


class _Subscription(NamedTuple):
    subscription: Any  # rclpy Subscription on the inbox node
    msg_type: type
    callback: Callable[[Any, int], Any]
    topic: str
    # messages deserialised by the inbox thread, handed out by the loop
    queue: collections.deque[Any]
    gaps: SequenceGaps  # messages lost before the inbox thread took them


class Inbox:
    """A loop stage that hands out the messages its thread took (``Stage``).

    Args:
        node: the node that holds the subscriptions; it must never be added to an
            executor. The inbox destroys it with itself.
        clock: stamps each message's receive time when the loop hands it out (the
            owner's clock: simulated time where the owner uses it).
        name: its name among the loop's components.
        writes: what its callbacks fill, for the loop's order (:mod:`rm_base.loop.data`):
            the plugins' commands, or the bridge's joint targets.
    """

    reads: tuple[str, ...] = ()

    def __init__(
        self, node: Any, clock: Any, name: str = STAGE_NAME, writes: tuple[str, ...] = (COMMANDS,)
    ) -> None:
        self.name = name
        self.writes = writes
        self._clock = clock
        self._node = node
        self._subscriptions: tuple[_Subscription, ...] = ()
        self.taken_by_topic: dict[str, int] = {}
        self.dropped_by_topic: dict[str, int] = {}
        # lost before the inbox thread could take them (publishers' sequence numbers)
        self.lost_by_topic: dict[str, int] = {}
        self._info = MessageInfo()  # the inbox thread's, filled by each take
        self._lost_log = LogThrottle(_LOG_PERIOD_NS)
        self._by_topic: dict[str, list[Any]] = {}
        self._local: set[str] = set()
        self.errors = 0
        self.receive_errors = 0
        self._error_log = LogThrottle(_LOG_PERIOD_NS)
        self._drop_log = LogThrottle(_LOG_PERIOD_NS)
        self._receive_log = LogThrottle(_LOG_PERIOD_NS)
        self._stopping = False
        # wakes the thread: a subscription came or went, or the inbox stops
        self._guard = GuardCondition(None, None, context=node.context)
        node.context.on_shutdown(self._wake)
        self._thread = threading.Thread(
            target=self._receive, name=f'{node.get_name()}-take', daemon=True
        )
        self._thread.start()

    @property
    def taken(self) -> int:
        """Messages handed to the callbacks so far, all topics."""
        return sum(self.taken_by_topic.values())

    @property
    def pending(self) -> int:
        """Messages taken from DDS that the loop has not handed out yet, all topics."""
        return sum(len(entry.queue) for entry in self._subscriptions)

    @property
    def dropped(self) -> int:
        """Messages dropped so far because the loop had not taken them, all topics."""
        return sum(self.dropped_by_topic.values())

    def subscribe(
        self, msg_type: type, topic: str, callback: Callable[[Any, int], Any], qos: Any
    ) -> None:
        """Hand topic's messages out in the loop: ``callback(msg, receive_ns)`` for each.

        Args:
            msg_type: message class.
            topic: a resolved (absolute) topic name.
            callback: stores the message (it runs in the loop thread).
            qos: subscription QoS (or history depth); its depth is the queue's too.
        """
        self.taken_by_topic.setdefault(topic, 0)
        self.dropped_by_topic.setdefault(topic, 0)
        if topic in self._local:
            return
        depth = queue_depth(qos)
        sub = self._node.create_subscription(msg_type, topic, _never_called, qos)
        entry = _Subscription(sub, msg_type, callback, topic, collections.deque(maxlen=depth),
                              SequenceGaps())
        # swapped whole: the loop and the thread may be iterating the old tuple
        self._subscriptions += (entry,)
        self._by_topic.setdefault(topic, []).append(sub)
        self._wake()

    def drop(self, topic: str) -> None:
        """Stop taking topic from DDS: its messages come from this process (loopback)."""
        self._local.add(topic)
        subs = self._by_topic.pop(topic, [])
        if subs:
            self._subscriptions = tuple(s for s in self._subscriptions if s.topic != topic)
            self._wake()
            for sub in subs:  # rclpy destroys each once the thread's wait lets go of it
                self._node.destroy_subscription(sub)

    def __call__(self, now_ns: int, dt: float) -> bool:
        """Hand every queued message to its callback; return whether there was one."""
        taken = 0
        counts = self.taken_by_topic
        receive_ns = 0
        for entry in self._subscriptions:
            queue = entry.queue
            while queue:
                data = queue.popleft()
                if not taken:
                    receive_ns = self._clock.now().nanoseconds
                taken += 1
                counts[entry.topic] += 1
                try:
                    entry.callback(data, receive_ns)
                except Exception:  # a plugin's callback must not stop the loop
                    self._callback_failed(entry.topic)
        return taken > 0

    def _callback_failed(self, topic: str) -> None:
        self.errors += 1
        more = self._error_log.due(time.monotonic_ns())
        if more is not None:
            _log.exception('a message on %s could not be handed out%s', topic, more)

    # -- the inbox thread -----------------------------------------------------------------

    def _wake(self) -> None:
        with contextlib.suppress(Exception):  # a shut-down context ends the thread anyway
            self._guard.trigger()

    def _receive(self) -> None:
        buffer = TakeBuffer()
        try:
            while not self._stopping:
                try:
                    self._wait_and_take(buffer)
                except Exception:
                    if self._stopping or not self._node.context.ok():
                        return
                    self._receive_failed()
                    time.sleep(_RETRY_S)
        finally:
            buffer.close()

    def _wait_and_take(self, buffer: TakeBuffer) -> None:
        """Wait and take until the subscriptions change or the inbox stops."""
        subs = self._subscriptions
        context = self._node.context.handle
        with contextlib.ExitStack() as in_use:  # rclpy destroys none of them meanwhile
            in_use.enter_context(context)
            in_use.enter_context(self._guard.handle)
            for entry in subs:
                try:
                    in_use.enter_context(entry.subscription.handle)
                except InvalidHandle:  # dropped meanwhile: a new tuple is there already
                    if subs is self._subscriptions:
                        raise
                    return
            wait_set = _rclpy.WaitSet(len(subs), 1, 0, 0, 0, 0, context)
            while not self._stopping and subs is self._subscriptions:
                wait_set.clear_entities()
                for entry in subs:
                    wait_set.add_subscription(entry.subscription.handle)
                wait_set.add_guard_condition(self._guard.handle)
                wait_set.wait(_WAIT_TIMEOUT_NS)  # the GIL is released while it waits
                ready = wait_set.get_ready_entities('subscription')
                for entry in subs:
                    if entry.subscription.handle.pointer in ready:
                        self._take_all(buffer, entry)

    def _take_all(self, buffer: TakeBuffer, entry: _Subscription) -> None:
        queue, info, gaps = entry.queue, self._info, entry.gaps
        while (data := buffer.take_serialized(entry.subscription, info)) is not None:
            if gaps.note(info):
                self.lost_by_topic[entry.topic] = gaps.lost
                more = self._lost_log.due(time.monotonic_ns())
                if more is not None:
                    _log.warning('%s: %d message(s) lost before they could be taken so far '
                                 "(DDS's keep-last history overwritten: a flood?)%s",
                                 entry.topic, gaps.lost, more)
            try:
                msg = deserialize_message(data, entry.msg_type)
            except Exception:  # counted and said; the thread takes on
                self._malformed(entry.topic)
                continue
            if len(queue) == queue.maxlen:
                self._dropped(entry.topic, queue.maxlen)
            queue.append(msg)

    def _malformed(self, topic: str) -> None:
        self.errors += 1
        more = self._error_log.due(time.monotonic_ns())
        if more is not None:
            _log.exception('a message on %s could not be deserialised%s', topic, more)

    def _dropped(self, topic: str, depth: int | None) -> None:
        self.dropped_by_topic[topic] += 1
        more = self._drop_log.due(time.monotonic_ns())
        if more is not None:
            _log.warning(
                '%s: %s messages wait for the loop (the QoS depth); the oldest was dropped%s',
                topic,
                depth,
                more,
            )

    def _receive_failed(self) -> None:
        self.receive_errors += 1
        more = self._receive_log.due(time.monotonic_ns())
        if more is not None:
            _log.exception('the inbox could not wait or take%s', more)

    def destroy(self) -> None:
        """Stop the inbox's thread; destroy its node (and its subscriptions)."""
        self._stopping = True
        self._wake()
        self._thread.join(_JOIN_TIMEOUT_S)
        if self._thread.is_alive():
            _log.warning(
                'the inbox thread of %s did not stop within %.0f s',
                self._node.get_name(),
                _JOIN_TIMEOUT_S,
            )
        self._subscriptions = ()
        self._guard.destroy()
        self._node.destroy_node()
