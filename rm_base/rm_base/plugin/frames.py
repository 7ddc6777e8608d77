"""The robot's TF: its plugins' transforms on /tf and /tf_static, and a tree to look them up.

Every plugin of a node shares one :class:`~rm_base.geometry.frame_tree.FrameTree`
(``PluginBase.frames``). A plugin that owns a transform sends it through a
:class:`FramePublisher` (``PluginBase.create_frame_publisher``): the tree takes it at
once, in the plugin's thread, so another plugin's lookup in the same tick sees it; and
it goes out as tf2_msgs/TFMessage on /tf (or /tf_static, latched), as tf2_ros's
broadcasters send it, through the plugin's edge publisher (never from the loop thread,
and not built when no other node listens). Where the virtualenv has no tf2_msgs,
scripts/setup.sh builds it from vendor/ (docs/ARCHITECTURE.md, "Frames").
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from geometry_msgs.msg import TransformStamped
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from tf2_msgs.msg import TFMessage

from rm_base.geometry.frame_tree import FrameTree
from rm_base.geometry.transforms import SE3
from rm_base.plugin.outbox import is_heard, publish_built

#: tf2_ros's TransformBroadcaster QoS: depth 100.
TF_QOS = QoSProfile(depth=100)
#: tf2_ros's StaticTransformBroadcaster QoS: latched for late joiners.
TF_STATIC_QOS = QoSProfile(
    depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
)

_NS_PER_S = 1_000_000_000

#: One transform a plugin sends: (parent frame, child frame, T_parent_child).
Link = tuple[str, str, SE3]


def transform_message(parent: str, child: str, transform: SE3, stamp_ns: int) -> TransformStamped:
    """``T_parent_child`` as a geometry_msgs/TransformStamped (header.frame_id = parent)."""
    msg = TransformStamped()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, _NS_PER_S)
    msg.header.frame_id = parent
    msg.child_frame_id = child
    t, q = msg.transform.translation, msg.transform.rotation
    t.x, t.y, t.z = (float(v) for v in transform.translation)
    q.x, q.y, q.z, q.w = transform.quaternion
    return msg


def tf_message(links: tuple[Link, ...], stamp_ns: int) -> TFMessage:
    """The links as one tf2_msgs/TFMessage, each stamped stamp_ns [ns]."""
    return TFMessage(transforms=[transform_message(p, c, t, stamp_ns) for p, c, t in links])


def se3_from_message(msg: TransformStamped) -> SE3:
    """The transform of a geometry_msgs/TransformStamped.

    Raises:
        InputRejectedError: a value is not finite or the rotation is not a unit quaternion.
    """
    t, q = msg.transform.translation, msg.transform.rotation
    return SE3.from_translation_quaternion((t.x, t.y, t.z), (q.x, q.y, q.z, q.w))


class FramePublisher:
    """Sends one plugin's transforms: into the node's tree, then on /tf or /tf_static.

    Args:
        frames: the node's frame tree.
        publisher: the plugin's edge publisher of TFMessage (``hand_over``).
        static: /tf_static: each send is the whole set of this publisher's static
            transforms (a late joiner gets the last message only).
    """

    def __init__(self, frames: FrameTree, publisher: Any, *, static: bool) -> None:
        self._frames = frames
        self._publisher = publisher
        self.static = static

    def send(self, links: Iterable[Link], stamp_ns: int) -> None:
        """Set each link in the tree, stamped stamp_ns [ns], and publish them if heard.

        Raises:
            InputRejectedError: a link would break the tree (see ``FrameTree.set``);
                the links before it were set, none was published.
        """
        links = tuple(links)
        for parent, child, transform in links:
            self._frames.set(parent, child, transform, stamp_ns, static=self.static)
        if is_heard(self._publisher):
            # built by the edge's thread (the transforms are frozen): not the loop's work
            publish_built(self._publisher, tf_message, links, stamp_ns)
