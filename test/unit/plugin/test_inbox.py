"""Inbox: the loop takes subscriptions itself; local topics never cross DDS."""

import logging

from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from rm_base.hardware.scheduler import Scheduler
from rm_base.node_main import inbox_node
from rm_base.plugin.inbox import Inbox
from rm_base.plugin.node_io import DdsJointIO
from rm_base.plugin.outbox import Outbox
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
    assert 'a subscription callback failed' in caplog.text
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
    assert io.loop_input('imu port', lambda: True) is False  # no loop: nothing would call it
    io.loop = Scheduler([], [])
    calls = []
    assert io.loop_input('imu port', lambda: calls.append(len(calls)) is None) is True
    plugin = lambda now_ns, dt: calls.append('plugin')  # noqa: E731
    plugin.name = 'plugin imu'
    io.loop.add_stage(plugin)
    io.loop.tick(0)
    assert calls == [0, 'plugin']
    assert dict(io.loop.component_stats())['imu port'].count == 1  # it took something: timed
    io.release()
    io.loop.tick(1_000_000)
    assert calls == [0, 'plugin', 'plugin']
    node.destroy_node()
