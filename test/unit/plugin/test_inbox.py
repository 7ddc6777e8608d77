"""Inbox: the loop takes subscriptions itself; local topics never cross DDS."""

import logging
import threading
import time

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rm_base.loop.data import PUBLISHED
from rm_base.loop.scheduler import Scheduler
from rm_base.plugin.inbox import MAX_QUEUED, Inbox, queue_depth
from rm_base.plugin.node_io import DdsJointIO
from rm_base.plugin.outbox import Outbox
from rm_base.ros import take as ros_take
from rm_base.ros.node_main import inbox_node
from std_msgs.msg import UInt32
from support.ros import wait_until


def _take_until(inbox, got, count, timeout=5.0):
    """Run the inbox stage like the loop does, until count messages were handed out."""

    def enough():
        inbox(0, 0.001)
        return len(got) >= count

    assert wait_until(enough, timeout)


def test_messages_reach_the_callback_only_when_the_loop_takes_them(ros_context):
    node = Node('inbox_test', context=ros_context)
    inbox = Inbox(inbox_node(node), node.get_clock())
    got = []
    inbox.subscribe(UInt32, '/inbox_cmd', lambda msg, ns: got.append((msg.data, ns)), 10)
    pub = node.create_publisher(UInt32, '/inbox_cmd', 10)
    assert wait_until(lambda: pub.get_subscription_count() == 1, 5.0)
    for i in range(3):
        pub.publish(UInt32(data=i))
    # nothing spins: the messages wait in DDS until the stage takes them, in order
    assert got == []
    _take_until(inbox, got, 3)
    assert [data for data, _ in got] == [0, 1, 2]
    assert all(ns > 0 for _, ns in got)
    assert inbox.taken == 3 and inbox.taken_by_topic == {'/inbox_cmd': 3}
    assert inbox(0, 0.001) is False  # an empty tick reports no work (not timed)
    inbox.destroy()
    node.destroy_node()


def test_a_failing_callback_is_counted_and_logged_and_the_next_message_still_arrives(
    ros_context, caplog
):
    node = Node('inbox_test', context=ros_context)
    inbox = Inbox(inbox_node(node), node.get_clock())
    got = []

    def callback(msg, ns):
        if msg.data == 0:
            raise ValueError('bad command')
        got.append(msg.data)

    inbox.subscribe(UInt32, '/inbox_cmd', callback, 10)
    pub = node.create_publisher(UInt32, '/inbox_cmd', 10)
    assert wait_until(lambda: pub.get_subscription_count() == 1, 5.0)
    pub.publish(UInt32(data=0))
    pub.publish(UInt32(data=1))
    with caplog.at_level(logging.ERROR, logger='rm_base.plugin.inbox'):
        _take_until(inbox, got, 1)
    assert got == [1] and inbox.errors == 1
    assert 'a message on /inbox_cmd could not be handed out' in caplog.text
    inbox.destroy()
    node.destroy_node()


def test_a_topic_published_in_process_reaches_the_plugins_by_the_outbox_not_from_dds(
    ros_context,
):
    node = Node('inbox_test', context=ros_context)
    io = DdsJointIO(node)
    io.outbox = Outbox()
    io.outbox.loopback = io.deliver
    io.inbox = Inbox(inbox_node(node), node.get_clock())
    got = []
    io.subscribe(UInt32, '/local_state', lambda msg, ns: got.append(msg.data), 10)
    publisher = io.create_publisher(UInt32, '/local_state', 10)
    msg = UInt32(data=7)
    publisher.publish(msg)
    msg.data = 8  # the plugin reuses its message: the others get the snapshot
    io.outbox.flush()  # the outbox thread's work: to the plugins, then on DDS
    assert got == [7]
    for _ in range(50):  # now it is on DDS too: the inbox must not hand it out again
        io.inbox(0, 0.001)
    assert got == [7] and io.inbox.taken == 0
    # a subscription made after the publisher is local from the start
    later = []
    io.subscribe(UInt32, '/local_state', lambda msg, ns: later.append(msg.data), 10)
    io.outbox.loopback_at_put = True  # lockstep: at once, in the publishing thread
    publisher.publish(UInt32(data=9))
    assert got == [7, 9] and later == [9]
    io.inbox.destroy()
    node.destroy_node()


def test_other_nodes_publishing_a_local_topic_are_reported(ros_context):
    node = Node('inbox_test', context=ros_context)
    io = DdsJointIO(node)
    io.outbox = Outbox()
    io.inbox = Inbox(inbox_node(node), node.get_clock())
    io.subscribe(UInt32, '/local_state', lambda msg, ns: None, qos_profile_sensor_data)
    io.create_publisher(UInt32, '/local_state', 10)
    io.create_publisher(UInt32, '/not_subscribed', 10)
    assert io.foreign_publishers() == {}
    other = Node('someone_else', context=ros_context)
    other.create_publisher(UInt32, '/local_state', 10)
    other.create_publisher(UInt32, '/not_subscribed', 10)
    assert wait_until(lambda: io.foreign_publishers() == {'/local_state': 1}, 5.0)
    other.destroy_node()
    io.inbox.destroy()
    node.destroy_node()


def test_input_stages_of_plugins_run_before_the_plugins_and_leave_on_release(ros_context):
    node = Node('inbox_test', context=ros_context)
    io = DdsJointIO(node)
    # no loop: nothing would call it
    assert io.loop_input('imu port', lambda: True, 'port imu') is False
    io.loop = Scheduler([], [])
    calls = []

    class Plugin:
        name, reads, writes = 'plugin imu', ('port imu',), (PUBLISHED,)

        def __call__(self, now_ns, dt):
            calls.append('plugin')

    io.loop.add_after_tick(lambda: None, reads=(PUBLISHED,))  # the ROS edge
    with io.loop.compose():
        io.loop.add_stage(Plugin())  # added first, runs after the port it reads
        assert io.loop_input('imu port', lambda: calls.append(len(calls)) is None, 'port imu')
    io.loop.tick(0)
    assert calls == [0, 'plugin']
    assert dict(io.loop.component_stats())['imu port'].count == 1  # it took something: timed
    io.release()
    io.loop.tick(1_000_000)
    assert calls == [0, 'plugin', 'plugin']
    node.destroy_node()


def test_messages_are_deserialised_by_the_inbox_thread_and_a_malformed_one_is_counted(
    ros_context, monkeypatch, caplog
):
    # Deserialising is most of a take's cost: it stays out of the loop's tick.
    from rm_base.plugin import inbox as inbox_module

    real = inbox_module.deserialize_message
    threads = []

    def deserialize(data, msg_type):
        threads.append(threading.get_ident())
        if len(threads) == 1:
            raise ValueError('malformed')
        return real(data, msg_type)

    monkeypatch.setattr(inbox_module, 'deserialize_message', deserialize)
    node = Node('inbox_test', context=ros_context)
    inbox = Inbox(inbox_node(node), node.get_clock())
    got = []
    inbox.subscribe(UInt32, '/inbox_raw', lambda msg, ns: got.append(msg.data), 10)
    pub = node.create_publisher(UInt32, '/inbox_raw', 10)
    assert wait_until(lambda: pub.get_subscription_count() == 1, 5.0)
    with caplog.at_level(logging.ERROR, logger='rm_base.plugin.inbox'):
        pub.publish(UInt32(data=7))
        pub.publish(UInt32(data=8))
        assert wait_until(lambda: inbox.pending == 1 and inbox.errors == 1, 5.0)
    assert 'a message on /inbox_raw could not be deserialised' in caplog.text
    assert inbox(0, 0.001) is True
    assert got == [8] and inbox.taken == 1
    assert len(threads) == 2 and threading.get_ident() not in threads
    inbox.destroy()
    node.destroy_node()


def test_the_loop_never_takes_from_dds_and_runs_on_while_a_take_blocks(ros_context, monkeypatch):
    # A take can wait a third of a second for Fast DDS's locks when a node joins
    # (docs/PERFORMANCE.md): only the inbox's thread may wait, never the loop.
    takers = set()
    blocked = threading.Event()
    release = threading.Event()
    gave_up = threading.Event()
    real_take = ros_take.TakeBuffer.take_serialized

    def take(buffer, subscription, info=None):
        takers.add(threading.get_ident())
        data = real_take(buffer, subscription, info)
        if data is not None:
            blocked.set()
            if not release.wait(10.0):  # a stage that waited for the take would end here
                gave_up.set()
        return data

    monkeypatch.setattr(ros_take.TakeBuffer, 'take_serialized', take)
    node = Node('inbox_test', context=ros_context)
    inbox = Inbox(inbox_node(node), node.get_clock())
    got = []
    inbox.subscribe(UInt32, '/inbox_block', lambda msg, ns: got.append(msg.data), 10)
    pub = node.create_publisher(UInt32, '/inbox_block', 10)
    assert wait_until(lambda: pub.get_subscription_count() == 1, 5.0)
    pub.publish(UInt32(data=99))
    assert blocked.wait(5.0)
    for _ in range(50):  # ticks while the thread's take is blocked
        assert inbox(0, 0.001) is False
    assert not gave_up.is_set()  # they all returned before the take did
    release.set()
    _take_until(inbox, got, 1)
    assert got == [99]
    assert takers and threading.get_ident() not in takers
    inbox.destroy()
    node.destroy_node()


def test_when_the_loop_falls_behind_the_oldest_messages_are_dropped_and_counted(
    ros_context, caplog
):
    node = Node('inbox_test', context=ros_context)
    inbox = Inbox(inbox_node(node), node.get_clock())
    got = []
    qos = QoSProfile(depth=3, reliability=ReliabilityPolicy.RELIABLE)
    inbox.subscribe(UInt32, '/inbox_behind', lambda msg, ns: got.append(msg.data), qos)
    pub = node.create_publisher(UInt32, '/inbox_behind', 10)
    assert wait_until(lambda: pub.get_subscription_count() == 1, 5.0)
    with caplog.at_level(logging.WARNING, logger='rm_base.plugin.inbox'):
        for i in range(8):  # one at a time: DDS's own queue never overflows
            pub.publish(UInt32(data=i))
            assert wait_until(lambda n=i + 1: inbox.pending + inbox.dropped == n, 5.0)
    assert inbox.pending == 3
    assert inbox.dropped_by_topic == {'/inbox_behind': 5}
    assert '/inbox_behind: 3 messages wait for the loop' in caplog.text
    assert inbox(0, 0.001) is True
    assert got == [5, 6, 7] and inbox.taken == 3 and inbox.pending == 0
    inbox.destroy()
    node.destroy_node()


def test_its_thread_ends_with_destroy_and_with_the_context():
    node = Node('inbox_test', context=(context := _started_context()))
    inbox = Inbox(inbox_node(node), node.get_clock())
    thread = inbox._thread
    assert thread.is_alive()
    inbox.destroy()
    assert not thread.is_alive()
    other = Inbox(inbox_node(node), node.get_clock())
    other.subscribe(UInt32, '/inbox_end', lambda msg, ns: None, 10)
    start = time.monotonic()
    context.shutdown()
    other._thread.join(5.0)
    assert not other._thread.is_alive()
    assert time.monotonic() - start < 2.0  # the shutdown wakes it: not its wait timeout
    assert other.receive_errors == 0


def _started_context():
    context = Context()
    rclpy.init(context=context)
    return context


@pytest.mark.parametrize(
    ('qos', 'depth'),
    [
        (10, 10),
        (0, MAX_QUEUED),
        (QoSProfile(depth=5), 5),
        (QoSProfile(depth=1, history=HistoryPolicy.KEEP_ALL), MAX_QUEUED),
        (qos_profile_sensor_data, qos_profile_sensor_data.depth),
    ],
)
def test_a_queue_is_as_deep_as_the_subscriptions_qos(qos, depth):
    assert queue_depth(qos) == depth


def test_a_qos_that_is_neither_a_profile_nor_a_depth_is_refused():
    with pytest.raises(TypeError, match='QoS'):
        queue_depth('sensor')
