"""What all plugins on one node share: actuator I/O and the record of who drives what.

That is the /actuator_cmd publisher, the joint-state view fed from /actuator_states, and
the record of which plugin drives which joint.

Created on first use per node (the host node, or a test's node) and kept as long as the
node lives, so plugins never create duplicate publishers or subscriptions. The plugin layer
uses rclpy only through the node object it is given (plus rclpy's QoS value types).
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Iterable
from typing import Any

from rclpy.qos import qos_profile_sensor_data

from rm_base.plugin.errors import JointClaimError
from rm_base.plugin.joints import JointStateView
from rm_msgs.msg import ActuatorCmd, ActuatorState

ACTUATOR_CMD_TOPIC = 'actuator_cmd'
"""Joint targets to the CAN bridge (relative: follows the node's namespace)."""

ACTUATOR_STATES_TOPIC = 'actuator_states'
"""Joint states from the CAN bridge (relative: follows the node's namespace)."""

# Reliable, keep last 10: a reliable writer matches both reliable and best-effort readers,
# so the bridge may pick either.
ACTUATOR_CMD_QOS_DEPTH = 10


class NodeIO:
    """Shared plugin I/O of one node. Use ``node_io(node)``, not the constructor."""

    def __init__(self, node: Any) -> None:
        self.actuator_cmd = node.create_publisher(
            ActuatorCmd, ACTUATOR_CMD_TOPIC, ACTUATOR_CMD_QOS_DEPTH
        )
        self.joint_states = JointStateView(node.get_logger())
        clock = node.get_clock()

        def on_actuator_states(msg: ActuatorState) -> None:
            self.joint_states.handle(msg, clock.now().nanoseconds)

        # Best effort matches a reliable or a best-effort bridge; an old state is worthless.
        self._subscription = node.create_subscription(
            ActuatorState, ACTUATOR_STATES_TOPIC, on_actuator_states, qos_profile_sensor_data
        )
        self._claims: dict[str, str] = {}
        self._lock = threading.Lock()

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


_BY_NODE: weakref.WeakKeyDictionary[Any, NodeIO] = weakref.WeakKeyDictionary()
_BY_NODE_LOCK = threading.Lock()


def node_io(node: Any) -> NodeIO:
    """Return the shared plugin I/O of node, creating it on first use."""
    with _BY_NODE_LOCK:
        io = _BY_NODE.get(node)
        if io is None:
            io = NodeIO(node)
            _BY_NODE[node] = io
        return io
