"""rm_robot with a few plugins in this process, and a probe node that records topics.

For plugin tests that watch only what a plugin publishes (a serial device fed through a
pty, say): the host and the probe share one EventsExecutor spun in a thread.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from typing import Any

import rclpy
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rm_base.host import RobotHost


class HostedPlugins:
    """A RobotHost made from flat parameter overrides, plus a probe; ``close()`` ends both."""

    def __init__(self, context: Any, overrides: Mapping[str, Any]) -> None:
        self.host = RobotHost(
            context=context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )
        self.probe = rclpy.create_node('probe', context=context)
        self.executor = EventsExecutor(context=context)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)

    def collect(self, msg_type: Any, topic: str, qos: Any = 50) -> list[Any]:
        """Every message on topic from now on, in a list that fills as they come."""
        received: list[Any] = []
        self.probe.create_subscription(msg_type, topic, received.append, qos)
        return received

    def start(self) -> HostedPlugins:
        """Start spinning the host and the probe."""
        self.executor.add_node(self.host)
        self.executor.add_node(self.probe)
        self._thread.start()
        return self

    def diagnostic(self, name: str, records: list[Any]) -> dict[str, Any] | None:
        """The newest status called name in recorded /diagnostics, as a dict of its values
        plus 'level' and 'message'."""
        for array in reversed(records):
            for status in array.status:
                if status.name == name:
                    values: dict[str, Any] = {kv.key: kv.value for kv in status.values}
                    values['level'] = status.level
                    values['message'] = status.message
                    return values
        return None

    def close(self) -> None:
        """Stop spinning, destroy both nodes."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
        self.host.destroy_node()
        self.probe.destroy_node()
        self.executor.shutdown()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)
