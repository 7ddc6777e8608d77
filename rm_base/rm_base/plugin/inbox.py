"""Inbox: subscriptions the control loop takes itself, each tick, with no executor.

A message an executor delivers costs the loop a thread switch and a wait for the GIL
behind the executor's thread (docs/PERFORMANCE.md). The inbox's subscriptions live on a
node that no executor spins (``rm_base.node_main.inbox_node`` makes one beside the owner):
DDS (native threads, no GIL) keeps what arrives in each subscription's queue, and the
loop's first stage, :meth:`Inbox.__call__`, takes every waiting message and hands it to
the plugin's callback, the same callback a subscription or ``inject`` runs. A command
reaches its plugin at the next tick.

Taking is rclpy's own ``handle.take_message`` (what its executors call; rclpy 7.1.6 has
no public take): ~2 µs per subscription when nothing is waiting.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

from rm_base.plugin.commands import LogThrottle

_log = logging.getLogger(__name__)

#: Stage name in the loop's timing statistics.
STAGE_NAME = 'commands'

# A failing callback is logged at most this often, with the count [ns].
_ERROR_LOG_PERIOD_NS = 1_000_000_000


def _never_called(msg: Any) -> None:  # the inbox takes the messages, no executor
    raise AssertionError('an executor spun the inbox node')


class Inbox:
    """A loop stage that takes the messages of its subscriptions (``Stage``).

    Args:
        node: the node that holds the subscriptions; it must never be added to an
            executor. The inbox destroys it with itself.
        clock: stamps each message's receive time (the owner's clock: simulated time
            where the owner uses it).
        name: its name among the loop's components.
    """

    def __init__(self, node: Any, clock: Any, name: str = STAGE_NAME) -> None:
        self.name = name
        self._clock = clock
        self._node = node
        self._subscriptions: tuple[tuple[Any, type, Callable[[Any, int], Any], str], ...] = ()
        self.taken_by_topic: dict[str, int] = {}
        self._by_topic: dict[str, list[Any]] = {}
        self._local: set[str] = set()
        self.errors = 0
        self._error_log = LogThrottle(_ERROR_LOG_PERIOD_NS)

    @property
    def taken(self) -> int:
        """Messages taken so far, all topics."""
        return sum(self.taken_by_topic.values())

    def subscribe(
        self, msg_type: type, topic: str, callback: Callable[[Any, int], Any], qos: Any
    ) -> None:
        """Take topic's messages in the loop: ``callback(msg, receive_ns)`` for each.

        Args:
            msg_type: message class.
            topic: a resolved (absolute) topic name.
            callback: stores the message (it runs in the loop thread).
            qos: subscription QoS.
        """
        self.taken_by_topic.setdefault(topic, 0)
        if topic in self._local:
            return
        sub = self._node.create_subscription(msg_type, topic, _never_called, qos)
        # swapped whole: the loop may be iterating the old tuple
        self._subscriptions += ((sub.handle, msg_type, callback, topic),)
        self._by_topic.setdefault(topic, []).append(sub)

    def drop(self, topic: str) -> None:
        """Stop taking topic from DDS: its messages come from this process (loopback)."""
        self._local.add(topic)
        subs = self._by_topic.pop(topic, [])
        if subs:
            self._subscriptions = tuple(s for s in self._subscriptions if s[3] != topic)
            for sub in subs:
                self._node.destroy_subscription(sub)

    def __call__(self, now_ns: int, dt: float) -> bool:
        """Take every waiting message; return whether there was one."""
        taken = 0
        counts = self.taken_by_topic
        for handle, msg_type, callback, topic in self._subscriptions:
            while True:
                with handle:
                    info = handle.take_message(msg_type, False)
                if info is None:
                    break
                taken += 1
                counts[topic] += 1
                try:
                    callback(info[0], self._clock.now().nanoseconds)
                except Exception:  # a plugin's callback must not stop the loop
                    self._callback_failed()
        return taken > 0

    def _callback_failed(self) -> None:
        self.errors += 1
        more = self._error_log.due(time.monotonic_ns())
        if more is not None:
            _log.exception('a subscription callback failed%s', more)

    def destroy(self) -> None:
        """Destroy the inbox's node (and its subscriptions)."""
        self._subscriptions = ()
        self._node.destroy_node()
