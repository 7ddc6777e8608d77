"""The robot live in Foxglove: its topics and parameters over the Foxglove WebSocket protocol.

``bringup --foxglove [PORT]`` starts this beside the robot, on loopback (a robot's laptop
reaches it through an SSH tunnel; a wider bind is the operator's choice of a firewall).
It uses the official ``foxglove-sdk`` server:

- every topic of the graph is a channel with its ROS 2 schema (``ros2msg``: the message
  definition and those it uses) and its messages as CDR, as a rosbag2 MCAP file holds
  them; a topic is subscribed only while a client subscribes it, so an idle view costs
  the robot nothing but discovery;
- /robot_description (std_msgs/String, latched): a URDF built from the config
  (:mod:`rm_bringup.robot_description`), so the 3D panel shows the chassis, the wheels,
  the gimbal and the barrel on /tf;
- the parameters of the robot's nodes (``/rm_robot.shooter.max_hz``), read and set from
  the parameter panel through each node's own set-parameters path: a live key is checked
  and applied as ``ros2 param set`` would, a start-up key is refused.

Topics are discovered by a timer of the view's node (the executor's thread); the server's
callbacks only record what clients want, and the node acts on it at its next tick.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, Sequence
from typing import Any

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from std_msgs.msg import String  # type: ignore[import-untyped]

from rm_bringup.cli.bag_types import BagTypes
from rm_bringup.cli.errors import CliError
from rm_bringup.cli.interfaces import get_message_class

DEFAULT_PORT = 8765
NODE_NAME = '_rm_foxglove'
_REFRESH_S = 0.25  # how often the graph and the clients' subscriptions are looked at
_LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


class FoxgloveView:
    """A Foxglove WebSocket server showing the robot (see the module docstring).

    Args:
        node: the view's own node (hidden), spun by the caller's executor.
        parameter_nodes: the nodes whose parameters the panel shows and sets.
        description: the URDF published on /robot_description, or None.
        host: the address to listen on; loopback unless the user says otherwise.
        port: the port; 0 picks a free one (``port`` says which), as does the default port
            when it is taken.
    """

    def __init__(
        self,
        node: Node,
        parameter_nodes: Sequence[Node],
        *,
        description: str | None = None,
        host: str = '127.0.0.1',
        port: int = DEFAULT_PORT,
    ) -> None:
        import foxglove
        from foxglove import Capability

        self._node = node
        self._parameter_nodes = {n.get_fully_qualified_name(): n for n in parameter_nodes}
        self._types = BagTypes()
        self._channels: dict[str, Any] = {}  # topic -> foxglove Channel
        self._subscriptions: dict[str, Any] = {}  # topic -> rclpy subscription
        self._lock = threading.Lock()
        self._wanted: dict[str, int] = {}  # topic -> subscribed clients (server thread)
        self._unknown: set[str] = set()  # topics whose type has no definition here
        if description is not None:
            self._description = node.create_publisher(String, '/robot_description', _LATCHED)
            self._description.publish(String(data=description))
        def start(on_port: int) -> Any:
            return foxglove.start_server(
                name='rm_ros2', host=host, port=on_port,
                capabilities=[Capability.Parameters], supported_encodings=['cdr'],
                server_listener=_listener(self),
            )

        try:
            self._server = start(port)
        except RuntimeError:
            if port != DEFAULT_PORT:
                raise
            self._server = start(0)  # the usual port is taken (another view): any free one
        self.port: int = self._server.port
        self._timer = node.create_timer(_REFRESH_S, self._refresh)
        self._refresh()

    # -- topics (executor thread) -------------------------------------------------------

    def _refresh(self) -> None:
        """Advertise new topics; subscribe what clients want and drop what they left."""
        for topic, types in self._node.get_topic_names_and_types():
            if topic not in self._channels and topic not in self._unknown and len(types) == 1:
                self._advertise(topic, types[0])
        with self._lock:
            wanted = {t for t, n in self._wanted.items() if n > 0}
        for topic in wanted - set(self._subscriptions):
            self._subscribe(topic)
        for topic in set(self._subscriptions) - wanted:
            self._node.destroy_subscription(self._subscriptions.pop(topic))

    def _advertise(self, topic: str, type_name: str) -> None:
        from foxglove import Channel, Schema

        try:
            self._types.ensure(type_name)
            definition, _ = self._types.typestore.generate_msgdef(type_name, ros_version=2)
            get_message_class(type_name)
        except (CliError, KeyError, ValueError):
            self._unknown.add(topic)  # a type not installed here: nothing to decode it with
            self._node.get_logger().info(f'foxglove: no definition of {type_name} ({topic})')
            return
        schema = Schema(name=type_name, encoding='ros2msg', data=definition.encode())
        self._channels[topic] = Channel(topic, schema=schema, message_encoding='cdr')

    def _subscribe(self, topic: str) -> None:
        channel = self._channels.get(topic)
        if channel is None:
            return
        msg_class = get_message_class(channel.schema_name())  # the topic's type
        # a latched topic is read as latched (its last message at once), the rest as
        # sensor data: best effort matches every publisher and never slows one down
        latched = any(
            info.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
            for info in self._node.get_publishers_info_by_topic(topic)
        )
        clock = self._node.get_clock()

        def forward(data: bytes) -> None:
            channel.log(data, log_time=clock.now().nanoseconds)

        self._subscriptions[topic] = self._node.create_subscription(
            msg_class, topic, forward, _LATCHED if latched else qos_profile_sensor_data,
            raw=True,
        )

    def _want(self, topic: str, delta: int) -> None:
        with self._lock:
            self._wanted[topic] = max(0, self._wanted.get(topic, 0) + delta)

    # -- parameters (server thread) -----------------------------------------------------

    def get_parameters(self, names: Iterable[str]) -> list[Any]:
        """``/<node>.<parameter>`` values; every parameter of every node for no names."""
        from foxglove import Parameter

        names = list(names)
        out = []
        for fqn, node in self._parameter_nodes.items():
            every = sorted(node.get_parameters_by_prefix(''))
            for parameter in node.get_parameters(every):
                full = f'{fqn}.{parameter.name}'
                if (not names or full in names) and parameter.value is not None:
                    out.append(Parameter(full, value=_native(parameter.value)))
        return out

    def set_parameters(self, parameters: Iterable[Any]) -> list[Any]:
        """Set each node's share of parameters in one call of its own; return the values now.

        A refused call leaves the node's values as they were, and the panel shows them.
        """
        from rclpy.parameter import Parameter as RosParameter

        warn = self._node.get_logger().warning
        by_node: dict[str, list[Any]] = {}
        for parameter in parameters:
            fqn, _, name = parameter.name.partition('.')
            node = self._parameter_nodes.get(fqn)
            if node is None or not node.has_parameter(name):
                warn(f'foxglove: no parameter {parameter.name}: not set')
                continue
            try:
                value = RosParameter(name, value=parameter.get_value())
            except TypeError as err:  # a dict, or a list of no one type: no parameter holds it
                warn(f'foxglove: {parameter.name}: not set: {err}')
                continue
            by_node.setdefault(fqn, []).append(value)
        for fqn, values in by_node.items():
            result = self._parameter_nodes[fqn].set_parameters_atomically(values)
            if not result.successful:
                warn(f'foxglove: {fqn}: {result.reason}')
        return self.get_parameters([p.name for p in parameters])

    def close(self) -> None:
        """Stop the server and drop the subscriptions."""
        self._server.stop()
        self._timer.cancel()
        for subscription in self._subscriptions.values():
            self._node.destroy_subscription(subscription)
        self._subscriptions.clear()
        for channel in self._channels.values():
            channel.close()


def _native(value: Any) -> Any:
    """A parameter value as foxglove takes it (arrays as lists)."""
    return list(value) if hasattr(value, '__len__') and not isinstance(value, str | bytes) else (
        value)


def _listener(view: FoxgloveView) -> Any:
    """The server's callbacks: what clients want, handed to the view."""
    import foxglove

    class Listener(foxglove.ServerListener):
        def on_subscribe(self, client: Any, channel: Any) -> None:
            view._want(channel.topic, +1)

        def on_unsubscribe(self, client: Any, channel: Any) -> None:
            view._want(channel.topic, -1)

        def on_get_parameters(
            self, client: Any, param_names: list[str], request_id: str | None = None
        ) -> list[Any]:
            return view.get_parameters(param_names)

        def on_set_parameters(
            self, client: Any, parameters: list[Any], request_id: str | None = None
        ) -> list[Any]:
            return view.set_parameters(parameters)

    return Listener()
