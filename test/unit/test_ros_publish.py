"""rm_base.ros.publish: rcl's serialised publish, with the GIL released while DDS sends."""

import ctypes
import threading
import time

import pytest
import rclpy
from rclpy.exceptions import InvalidHandle
from rclpy.node import Node
from rclpy.serialization import serialize_message
from rm_base.ros import publish as ros_publish
from std_msgs.msg import String
from support.ros import spin_until, wait_until


def _subscribed(ros_context, topic):
    node = Node('ros_publish_test', context=ros_context)
    publisher = node.create_publisher(String, topic, 10)
    got = []
    node.create_subscription(String, topic, lambda msg: got.append(msg.data), 10)
    assert wait_until(lambda: publisher.get_subscription_count() == 1, 5.0)
    return node, publisher, got


def test_a_message_and_its_serialised_bytes_both_arrive_in_order(ros_context):
    node, publisher, got = _subscribed(ros_context, '/ros_publish_order')
    ros_publish.publish(publisher, String(data='one'))
    data = serialize_message(String(data='two'))
    assert b'\x00' in data  # CDR has zero bytes: nothing is cut at the first
    ros_publish.publish(publisher, data)
    assert spin_until(node, lambda: len(got) == 2)
    assert got == ['one', 'two']
    node.destroy_node()


def test_a_destroyed_publisher_raises_and_publishes_nothing(ros_context):
    node, publisher, got = _subscribed(ros_context, '/ros_publish_gone')
    node.destroy_publisher(publisher)
    with pytest.raises(InvalidHandle):
        ros_publish.publish(publisher, String(data='late'))
    assert got == []
    node.destroy_node()


def test_a_shut_down_context_is_a_publish_error_naming_the_topic():
    from rclpy.context import Context

    context = Context()
    rclpy.init(context=context)
    node = Node('ros_publish_shut', context=context)
    publisher = node.create_publisher(String, '/ros_publish_shut', 10)
    context.shutdown()
    with pytest.raises(ros_publish.PublishError, match='/ros_publish_shut'):
        ros_publish.publish(publisher, String(data='late'))


def test_the_functions_it_loads_let_other_threads_run_while_they_block():
    # A C call that blocks 200 ms, loaded the way rcl's publish is: another Python thread
    # must keep running meanwhile (with the GIL held it would stop until the call returns).
    usleep = ros_publish.load_function('libc.so.6', 'usleep', (ctypes.c_uint,), ctypes.c_int)
    ticks = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.005)

    ticker = threading.Thread(target=tick)
    ticker.start()
    time.sleep(0.02)
    start = time.monotonic()
    usleep(200_000)
    end = time.monotonic()
    stop.set()
    ticker.join()
    during = [t for t in ticks if start < t < end]
    assert end - start >= 0.19
    assert len(during) >= 5  # generous: 5 ms sleeps over 200 ms give about 40


def test_a_stand_in_publisher_publishes_the_message_itself():
    class StandIn:
        def __init__(self):
            self.published = []

        def publish(self, msg):
            self.published.append(msg)

    stand_in = StandIn()
    ros_publish.publish(stand_in, String(data='x'))
    assert stand_in.published == [String(data='x')]
