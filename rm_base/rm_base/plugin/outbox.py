"""Outbox: messages built in the control loop, published by a thread of the ROS edge.

rclpy's publish hands the message to DDS; on the 1 kHz loop thread that would put DDS
inside the robot (docs/ARCHITECTURE.md, "ROS at the edge"). A plugin's publisher is
wrapped instead (:meth:`Outbox.wrap`): ``publish(msg)`` serialises the message (a C call,
~10 µs: the snapshot, so the plugin may reuse its message object at once), appends the
bytes to a queue, and the outbox thread publishes them in order. Appending never blocks.
The queue is bounded: if the edge falls behind, the oldest messages are dropped and
counted (a state message is superseded by the next one anyway).

Who wakes the thread: each ``put``, or, once :meth:`Outbox.pace` tied it to a control
loop, the end of each tick (``wake``), so that it publishes in the loop's idle time and
never asks for the interpreter in the middle of a tick.
"""

from __future__ import annotations

import collections
import logging
import threading
from collections.abc import Callable
from typing import Any

from rclpy.serialization import serialize_message

_log = logging.getLogger(__name__)

#: Messages held at most before the oldest are dropped.
MAX_QUEUED = 1000


class _EdgePublisher:
    """Stands in for an rclpy publisher: ``publish`` goes through the outbox."""

    def __init__(self, outbox: Outbox, publisher: Any) -> None:
        self._outbox = outbox
        self.publisher = publisher
        self.topic_name = publisher.topic_name

    def publish(self, msg: Any) -> None:
        self._outbox.put(self.publisher, msg)

    def get_subscription_count(self) -> int:
        return self.publisher.get_subscription_count()

    def wait_for_all_acked(self, *args: Any, **kwargs: Any) -> bool:
        self._outbox.flush()
        return self.publisher.wait_for_all_acked(*args, **kwargs)


class Outbox:
    """A queue of (publisher, serialised message) and the thread that publishes them.

    Args:
        name: thread name.
        max_queued: messages held at most before the oldest are dropped.
    """

    def __init__(self, name: str = 'ros-edge-publish', max_queued: int = MAX_QUEUED) -> None:
        # (publisher, serialised message, its type if the thread hands it to the loopback)
        self._queue: collections.deque[tuple[Any, bytes, type | None]] = collections.deque(
            maxlen=max_queued
        )
        self._wake = threading.Event()
        self._stop = False
        self._publish_lock = threading.Lock()  # flush() and the thread publish in order
        self.published = 0
        self.dropped = 0
        self.errors = 0
        self.loopback_errors = 0
        self._paced = False
        # Also hands each message to the in-process subscribers of its topic
        # (``loopback(topic, raw, msg_type)``: the serialised snapshot), so nothing
        # inside the robot waits on DDS: from the outbox thread, before publishing it,
        # or, with ``loopback_at_put`` (lockstep: the same tick on every run), at once.
        self.loopback: Callable[[str, bytes, type], object] | None = None
        self.loopback_at_put = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def wrap(self, publisher: Any) -> _EdgePublisher:
        """Return a publisher whose messages go through this outbox."""
        return _EdgePublisher(self, publisher)

    def put(self, publisher: Any, msg: Any) -> None:
        """Queue msg, serialised now, for publisher (any thread; never blocks)."""
        raw = serialize_message(msg)
        in_thread = self.loopback is not None and not self.loopback_at_put
        if self.loopback is not None and not in_thread:
            self.loopback(publisher.topic_name, raw, type(msg))
        queue = self._queue
        if len(queue) == queue.maxlen:
            self.dropped += 1
        queue.append((publisher, raw, type(msg) if in_thread else None))
        if not self._paced:
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
                publisher, msg, loop_type = queue.popleft()
                if loop_type is not None:
                    self._hand_back(publisher.topic_name, msg, loop_type)
                try:
                    publisher.publish(msg)
                    self.published += 1
                except Exception as err:  # e.g. the context is shutting down
                    self.errors += 1
                    if self.errors == 1:
                        _log.error('publishing %s failed: %r', publisher.topic_name, err)

    def _hand_back(self, topic: str, raw: bytes, msg_type: type) -> None:
        try:
            self.loopback(topic, raw, msg_type)
        except Exception as err:  # a subscriber's callback: the message is still published
            self.loopback_errors += 1
            if self.loopback_errors == 1:
                _log.error('in-process delivery on %s failed: %r', topic, err)

    def stop(self, timeout_s: float = 2.0) -> None:
        """Publish what is queued, then end the thread. Idempotent."""
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
