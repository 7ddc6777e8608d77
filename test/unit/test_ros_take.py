"""rm_base.ros.take: rcl's serialised take, with the GIL released while rcl takes."""

import ctypes

import pytest
import rclpy
from rclpy.context import Context
from rclpy.exceptions import InvalidHandle
from rclpy.node import Node
from rclpy.serialization import deserialize_message
from rm_base.ros.take import TakeBuffer, TakeError
from std_msgs.msg import String
from support.ros import wait_until


def _pair(context, topic):
    node = Node('ros_take_test', context=context)
    subscription = node.create_subscription(String, topic, lambda msg: None, 10)
    publisher = node.create_publisher(String, topic, 10)
    assert wait_until(lambda: publisher.get_subscription_count() == 1, 5.0)
    return node, subscription, publisher


def _first(take, timeout=5.0):
    """take()'s first result that is not None."""
    got = []
    assert wait_until(lambda: got.append(take()) or got[-1] is not None, timeout)
    return got[-1]


def _take_one(buffer, subscription):
    return _first(lambda: buffer.take(subscription, String))


def test_messages_come_in_order_then_none_and_the_buffer_grows_for_a_large_one(ros_context):
    node, subscription, publisher = _pair(ros_context, '/ros_take_order')
    buffer = TakeBuffer(capacity=4)  # smaller than any message: rmw must grow it
    assert buffer.take(subscription, String) is None
    publisher.publish(String(data='x' * 5000))
    publisher.publish(String(data='short'))
    assert _take_one(buffer, subscription).data == 'x' * 5000
    assert _take_one(buffer, subscription).data == 'short'  # the length, not the capacity
    assert buffer.take(subscription, String) is None
    publisher.publish(String(data='as bytes'))
    data = _first(lambda: buffer.take_serialized(subscription))
    assert isinstance(data, bytes) and deserialize_message(data, String).data == 'as bytes'
    buffer.close()
    buffer.close()  # idempotent
    with pytest.raises(ValueError, match='closed'):
        buffer.take(subscription, String)
    node.destroy_node()


def test_a_destroyed_subscription_raises(ros_context):
    node, subscription, _publisher = _pair(ros_context, '/ros_take_gone')
    node.destroy_subscription(subscription)
    buffer = TakeBuffer()
    with pytest.raises(InvalidHandle):
        buffer.take(subscription, String)
    buffer.close()
    node.destroy_node()


def test_a_shut_down_context_has_nothing_to_take():
    context = Context()
    rclpy.init(context=context)
    _node, subscription, _publisher = _pair(context, '/ros_take_shut')
    context.shutdown()
    buffer = TakeBuffer()
    assert buffer.take(subscription, String) is None
    buffer.close()


class _ZeroedSubscription:
    """A subscription whose rcl struct was never initialised (rcl finds it invalid)."""

    topic_name = '/ros_take_invalid'

    def __init__(self):
        self._struct = ctypes.create_string_buffer(64)  # rcl_subscription_t: impl NULL
        self.handle = self

    @property
    def pointer(self):
        return ctypes.addressof(self._struct)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_an_error_from_rcl_is_a_take_error_naming_the_topic_and_the_buffer_still_works(
    ros_context,
):
    buffer = TakeBuffer()
    with pytest.raises(TakeError, match='/ros_take_invalid'):
        buffer.take(_ZeroedSubscription(), String)
    node, subscription, publisher = _pair(ros_context, '/ros_take_after_error')
    publisher.publish(String(data='next'))
    assert _take_one(buffer, subscription).data == 'next'
    buffer.close()
    node.destroy_node()


def test_messages_dds_dropped_before_the_take_are_counted_from_the_sequence_numbers(ros_context):
    # The finding: messages dropped by a subscription's keep-last queue during a flood
    # were counted nowhere. A depth-3 reader given 20 messages keeps the last 3.
    from rm_base.ros.take import MessageInfo, SequenceGaps

    node = Node('ros_take_gaps', context=ros_context)
    subscription = node.create_subscription(String, '/ros_take_gaps', lambda msg: None, 3)
    publisher = node.create_publisher(String, '/ros_take_gaps', 3)
    assert wait_until(lambda: publisher.get_subscription_count() == 1, 5.0)
    buffer, info, gaps = TakeBuffer(), MessageInfo(), SequenceGaps()
    publisher.publish(String(data='first'))
    assert _first(lambda: buffer.take_serialized(subscription, info)) is not None
    assert gaps.note(info) == 0 and info.publication_sequence_number > 0
    for index in range(20):
        publisher.publish(String(data=str(index)))
    taken = []

    def take_all():
        while (data := buffer.take_serialized(subscription, info)) is not None:
            gaps.note(info)
            taken.append(deserialize_message(data, String).data)
        return taken[-1:] == ['19']

    assert wait_until(take_all, 5.0)
    assert taken == ['17', '18', '19']
    assert gaps.lost == 17
    buffer.close()
    node.destroy_node()


def test_sequence_gaps_count_per_publisher_and_ignore_rmws_without_numbers():
    from rm_base.ros.take import MessageInfo, SequenceGaps

    def info(number, gid):
        i = MessageInfo()
        i.publication_sequence_number = number
        i.publisher_gid.data[0] = gid
        return i

    gaps = SequenceGaps()
    assert [gaps.note(info(n, g)) for n, g in ((1, 1), (1, 2), (4, 1), (2, 2), (0, 3), (0, 3))] \
        == [0, 0, 2, 0, 0, 0]
    assert gaps.note(info(1, 1)) == 0  # a publisher that started over
    assert gaps.lost == 2
