"""Outbox: messages built in the control loop, published by a thread of the ROS edge.

rclpy's publish hands the message to DDS; on the 1 kHz loop thread that would put DDS
inside the robot (docs/ARCHITECTURE.md, "ROS at the edge"). A plugin's publisher is
wrapped instead (:meth:`Outbox.wrap`): ``publish(msg)`` serialises the message (a C call,
~10 µs: the snapshot, so the plugin may reuse its message object at once), appends the
bytes to a queue, and the outbox thread publishes them in order. Appending never blocks.
A publisher that hands its messages over (``hand_over``: a new message for each publish,
never changed after) skips the snapshot: the robot's own subscribers get that object at
once, in the publishing thread (their callbacks only store it), and the outbox thread
serialises it for DDS if another node subscribes.
A report can also be handed over unbuilt (``publish_built(build, *values)``): the loop
only queues the function and an immutable snapshot of the values, and the outbox thread
builds the message, hands it to the robot's subscribers and publishes it. Building and
serialising a state message costs the loop about as much as a plugin's control step
(docs/PERFORMANCE.md, "No DDS call from the loop"); this way it costs a tuple. Where the
loopback is immediate (``loopback_at_put``: lockstep; a hand-over publisher) or the topic
latched, the message is built at once instead.
The queue is bounded: if the edge falls behind, the oldest messages are dropped, counted
and said in a warning at most once a second (a state message is superseded by the next
one anyway).

A message nobody would get is not serialised at all: no plugin of this process listens
to its topic, no other node subscribes (the publisher's matched subscriptions) and the
topic keeps nothing for late joiners (volatile durability). Such messages are counted
(``unheard``); the first subscriber gets the next one, as it would from DDS.
A latched topic's last message is kept (:meth:`Outbox.last_latched`), so a plugin of this
process that subscribes later gets it, as a transient-local DDS subscriber would.

Who wakes the thread: each ``put``, or, once :meth:`Outbox.pace` tied it to a control
loop, the end of each tick (``wake``), so that it publishes in the loop's idle time and
never asks for the interpreter in the middle of a tick.
"""

from __future__ import annotations

import collections
import logging
import threading
import time
from collections.abc import Callable
from typing import Any, NamedTuple

from rclpy.qos import DurabilityPolicy
from rclpy.serialization import serialize_message

from rm_base.plugin.commands import LogThrottle
from rm_base.ros.publish import publish

_log = logging.getLogger(__name__)

#: Messages held at most before the oldest are dropped.
MAX_QUEUED = 1000
# A failing build function is logged at most this often, with the count [ns].
_BUILD_LOG_PERIOD_NS = 1_000_000_000


def _always(topic: str) -> bool:
    return True


def _latched(publisher: Any) -> bool:
    # a late joiner gets the last message: every message counts
    return bool(publisher.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL)


class _Build(NamedTuple):
    """A message the outbox thread builds: ``build(*values)``."""

    build: Callable[..., Any]
    values: tuple[Any, ...]


def publish_built(publisher: Any, build: Callable[..., Any], *values: Any) -> None:
    """Publish ``build(*values)``, built by the outbox thread where there is one.

    values must not change after the call (numbers, strings, tuples); build must return a
    new message each call. With a plain rclpy publisher the message is built and published
    at once.
    """
    if isinstance(publisher, _EdgePublisher):
        publisher.publish_built(build, *values)
    else:
        publisher.publish(build(*values))


def is_heard(publisher: Any) -> bool:
    """Whether a message published now would reach anyone (an rclpy or outbox publisher)."""
    if isinstance(publisher, _EdgePublisher):
        return publisher.heard()
    return _latched(publisher) or publisher.get_subscription_count() > 0


class _EdgePublisher:
    """Stands in for an rclpy publisher: ``publish`` goes through the outbox."""

    def __init__(self, outbox: Outbox, publisher: Any, hand_over: bool) -> None:
        self._outbox = outbox
        self.publisher = publisher
        self.topic_name = publisher.topic_name
        self.hand_over = hand_over
        self.latched = _latched(publisher)

    def publish(self, msg: Any) -> None:
        self._outbox.put(self, msg)

    def publish_built(self, build: Callable[..., Any], *values: Any) -> None:
        """Publish build(*values), built by the outbox thread (see :func:`publish_built`)."""
        self._outbox.put_built(self, build, values)

    def heard(self) -> bool:
        """Whether a message published now would reach anyone (else it is not sent)."""
        return self._outbox.heard(self)

    def get_subscription_count(self) -> int:
        return int(self.publisher.get_subscription_count())

    def wait_for_all_acked(self, *args: Any, **kwargs: Any) -> bool:
        self._outbox.flush()
        return bool(self.publisher.wait_for_all_acked(*args, **kwargs))


class Outbox:
    """A queue of (publisher, serialised message) and the thread that publishes them.

    Args:
        name: thread name.
        max_queued: messages held at most before the oldest are dropped.
    """

    def __init__(self, name: str = 'ros-edge-publish', max_queued: int = MAX_QUEUED) -> None:
        # (edge publisher, serialised message, the message handed over or a _Build, its
        # type (None: the built message's), whether the thread hands it to the loopback,
        # whether it goes on DDS)
        self._queue: collections.deque[tuple[_EdgePublisher, Any, type | None, bool, bool]]
        self._queue = collections.deque(maxlen=max_queued)
        self._wake = threading.Event()
        self._stop = False
        self._publish_lock = threading.Lock()  # flush() and the thread publish in order
        self.published = 0
        self.dropped = 0
        self.errors = 0
        self.build_errors = 0
        self._build_log = LogThrottle(_BUILD_LOG_PERIOD_NS)
        self._drop_log = LogThrottle(_BUILD_LOG_PERIOD_NS)
        self.loopback_errors = 0
        self._paced = False
        # Also hands each message to the in-process subscribers of its topic
        # (``loopback(topic, data, msg_type)``: the serialised snapshot, or the message
        # itself if handed over), so nothing inside the robot waits on DDS: from the
        # outbox thread, before publishing it, or at once with ``loopback_at_put``
        # (lockstep: the same tick on every run) or for a message handed over.
        self.loopback: Callable[[str, Any, type], object] | None = None
        self.loopback_at_put = False
        # whether the loopback has subscribers on a topic (unknown: assume so)
        self.listens: Callable[[str], bool] = _always
        self.unheard = 0
        # latched topic -> (its last message: serialised or handed over, its type)
        self._latched: dict[str, tuple[Any, type]] = {}
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def wrap(self, publisher: Any, hand_over: bool = False) -> _EdgePublisher:
        """Return a publisher whose messages go through this outbox.

        Args:
            publisher: an rclpy publisher.
            hand_over: the caller builds a new message for each publish and never changes
                it after: no snapshot is taken (see the module docstring).
        """
        return _EdgePublisher(self, publisher, hand_over)

    def heard(self, edge: _EdgePublisher) -> bool:
        """Whether a message put for edge now would reach anyone."""
        local, outside = self._audience(edge)
        return local or outside

    def last_latched(self, topic: str) -> tuple[Any, type] | None:
        """The last message put on a latched topic (serialised or handed over) and its type."""
        return self._latched.get(topic)

    def put(self, edge: _EdgePublisher, msg: Any) -> None:
        """Queue msg for edge's publisher (any thread; never blocks)."""
        self._put(edge, msg, not edge.hand_over, self._audience(edge))

    def put_built(
        self, edge: _EdgePublisher, build: Callable[..., Any], values: tuple[Any, ...]
    ) -> None:
        """Queue build(*values) for edge's publisher, to be built by the thread.

        Built at once instead where the robot's subscribers get messages at once
        (``loopback_at_put``, a hand-over publisher) or the topic is latched.
        """
        audience = self._audience(edge)
        local, outside = audience
        if not (local or outside):
            self.unheard += 1
            return
        if self.loopback_at_put or edge.latched or (local and edge.hand_over):
            self._put(edge, build(*values), False, audience)  # new: nobody else holds it
            return
        self._enqueue(edge, _Build(build, values), None, local, outside)

    def _audience(self, edge: _EdgePublisher) -> tuple[bool, bool]:
        """Whether a plugin of this process, and whether anyone outside, gets edge's messages."""
        local = self.loopback is not None and self.listens(edge.topic_name)
        outside = edge.latched or edge.publisher.get_subscription_count() > 0
        return local, bool(outside)

    def _put(
        self, edge: _EdgePublisher, msg: Any, snapshot: bool, audience: tuple[bool, bool]
    ) -> None:
        """Queue msg (serialised first if snapshot) for its audience (see _audience)."""
        topic = edge.topic_name
        local, outside = audience
        if not (local or outside):
            self.unheard += 1
            return
        data = serialize_message(msg) if snapshot else msg
        if edge.latched:
            self._latched[topic] = (data, type(msg))
        # a message not snapshot costs its subscribers no copy: they get it at once
        if local and (self.loopback_at_put or not snapshot):
            self._hand_back(topic, data, type(msg))
            local = False
        if local or outside:
            self._enqueue(edge, data, type(msg), local, outside)

    def _enqueue(
        self, edge: _EdgePublisher, data: Any, msg_type: type | None, local: bool, outside: bool
    ) -> None:
        queue = self._queue
        if len(queue) == queue.maxlen:
            self.dropped += 1
            more = self._drop_log.due(time.monotonic_ns())
            if more is not None:
                _log.warning('the ROS edge is %d messages behind: the oldest dropped (%d so '
                             'far)%s', queue.maxlen, self.dropped, more)
        queue.append((edge, data, msg_type, local, outside))
        if self._stop:  # no thread any more: a late message (zero output) still goes out
            self.flush()
        elif not self._paced:
            self._wake.set()

    def pace(self) -> None:
        """From now on publish only when :meth:`wake` is called (at the end of a tick)."""
        self._paced = True

    def wake(self) -> None:
        """Let the thread publish what is queued (the loop's after-tick callback)."""
        if self._queue:
            self._wake.set()

    def start(self) -> None:
        """Start the publishing thread."""
        self._thread.start()

    def flush(self) -> None:
        """Publish everything queued now, in the calling thread."""
        with self._publish_lock:
            queue = self._queue
            while queue:
                edge, data, msg_type, local, outside = queue.popleft()
                if isinstance(data, _Build):
                    data = self._build(edge, data)
                    if data is None:
                        continue
                if local:
                    self._hand_back(edge.topic_name, data, msg_type or type(data))
                if not outside:
                    continue
                try:
                    publish(edge.publisher, data)  # bytes go out as they are; DDS without the GIL
                    self.published += 1
                except Exception as err:  # e.g. the context is shutting down
                    self.errors += 1
                    if self.errors == 1:
                        _log.error('publishing %s failed: %r', edge.topic_name, err)

    def _build(self, edge: _EdgePublisher, job: _Build) -> Any:
        """The message job builds, or None if the plugin's build function failed (logged)."""
        try:
            return job.build(*job.values)
        except Exception as err:  # a plugin's function: the thread must go on
            self.build_errors += 1
            more = self._build_log.due(time.monotonic_ns())
            if more is not None:
                _log.error('building a message for %s failed: %r%s', edge.topic_name, err, more)
            return None

    def _hand_back(self, topic: str, data: Any, msg_type: type) -> None:
        if self.loopback is None:
            return
        try:
            self.loopback(topic, data, msg_type)
        except Exception as err:  # a subscriber's callback: the message is still published
            self.loopback_errors += 1
            if self.loopback_errors == 1:
                _log.error('in-process delivery on %s failed: %r', topic, err)

    def stop(self, timeout_s: float = 2.0) -> None:
        """Publish what is queued, then end the thread. Idempotent.

        A message put afterwards is published at once, in the thread that puts it.
        """
        self._stop = True
        self._wake.set()
        if self._thread.is_alive():
            self._thread.join(timeout_s)
        self.flush()

    def _run(self) -> None:
        while not self._stop:
            self._wake.wait()
            self._wake.clear()
            self.flush()
