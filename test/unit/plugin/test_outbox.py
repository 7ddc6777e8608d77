"""Outbox: messages from the loop published by the edge's thread, in order, never blocking."""

import logging
import threading

import pytest
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.serialization import deserialize_message
from rm_base.plugin.outbox import Outbox, is_heard, publish_built
from std_msgs.msg import UInt32
from support.ros import wait_until


class FakePublisher:
    topic_name = '/fake'

    def __init__(self, subscribers=1, durability=DurabilityPolicy.VOLATILE):
        self.published = []
        self.threads = set()
        self.subscribers = subscribers
        self.qos_profile = QoSProfile(depth=10, durability=durability)

    def get_subscription_count(self):
        return self.subscribers

    def publish(self, msg):  # as rclpy's: serialised bytes or a message
        if isinstance(msg, bytes):
            msg = deserialize_message(msg, UInt32)
        self.published.append(msg.data)
        self.threads.add(threading.current_thread().name)


def test_messages_are_published_in_order_by_the_outbox_thread():
    box = Outbox('test-publish')
    pub = FakePublisher()
    wrapped = box.wrap(pub)
    box.start()
    try:
        for i in range(100):
            wrapped.publish(UInt32(data=i))
        assert wait_until(lambda: len(pub.published) == 100, 5.0)
    finally:
        box.stop()
    assert pub.published == list(range(100))
    assert pub.threads == {'test-publish'}


def test_a_message_changed_after_publish_goes_out_as_it_was_published():
    # Plugins reuse one message object per topic: the outbox keeps a snapshot.
    box = Outbox()
    pub = FakePublisher()
    msg = UInt32(data=1)
    box.wrap(pub).publish(msg)
    msg.data = 2
    box.stop()
    assert pub.published == [1]


def test_stop_publishes_what_is_still_queued():
    box = Outbox()
    pub = FakePublisher()
    box.wrap(pub).publish(UInt32(data=7))  # never started: stop() flushes
    box.stop()
    assert pub.published == [7]


def test_a_message_put_after_stop_is_published_at_once_in_the_putting_thread():
    # e.g. a plugin's zero output when it is disabled after the host's outbox stopped
    box = Outbox('test-publish')
    pub = FakePublisher()
    wrapped = box.wrap(pub)
    box.start()
    box.stop()
    wrapped.publish(UInt32(data=3))
    assert pub.published == [3]
    assert pub.threads == {threading.current_thread().name}


def test_when_the_edge_falls_behind_expect_the_oldest_dropped_counted_and_said_once(caplog):
    box = Outbox(max_queued=3)
    pub = FakePublisher()
    wrapped = box.wrap(pub)
    with caplog.at_level(logging.WARNING, logger='rm_base.plugin.outbox'):
        for i in range(5):
            wrapped.publish(UInt32(data=i))
    box.stop()
    assert pub.published == [2, 3, 4]
    assert box.dropped == 2
    said = [r.getMessage() for r in caplog.records if 'behind' in r.getMessage()]
    assert len(said) == 1 and '3 messages behind' in said[0]


def test_loopback_gets_the_snapshot_at_once_with_the_topic():
    box = Outbox()
    box.loopback_at_put = True
    got = []
    box.loopback = lambda topic, raw, msg_type: got.append(
        (topic, deserialize_message(raw, msg_type))
    )
    msg = UInt32(data=5)
    box.wrap(FakePublisher()).publish(msg)
    msg.data = 6
    assert [(topic, m.data) for topic, m in got] == [('/fake', 5)]
    box.stop()


def test_loopback_from_the_thread_gets_the_snapshot_before_it_is_published():
    box = Outbox()
    pub = FakePublisher()
    order = []
    box.loopback = lambda topic, raw, msg_type: order.append(
        ('local', deserialize_message(raw, msg_type).data)
    )
    pub.publish = lambda raw: order.append(('dds', deserialize_message(raw, UInt32).data))
    msg = UInt32(data=5)
    box.wrap(pub).publish(msg)
    msg.data = 6
    assert order == []  # nothing in the publishing (loop) thread
    box.flush()
    assert order == [('local', 5), ('dds', 5)]


def test_a_failing_loopback_is_counted_and_the_message_still_published():
    box = Outbox()
    pub = FakePublisher()

    def fail(topic, raw, msg_type):
        raise ValueError('bad subscriber')

    box.loopback = fail
    box.wrap(pub).publish(UInt32(data=3))
    box.flush()
    assert box.loopback_errors == 1 and pub.published == [3]


def test_a_message_nobody_would_get_is_not_serialised_and_is_counted():
    box = Outbox()
    pub = FakePublisher(subscribers=0)
    box.loopback = lambda topic, raw, msg_type: pytest.fail('no plugin listens')
    box.listens = lambda topic: False
    wrapped = box.wrap(pub)
    wrapped.publish(UInt32(data=1))
    pub.subscribers = 1  # someone subscribes: the next message is theirs
    wrapped.publish(UInt32(data=2))
    box.stop()
    assert pub.published == [2] and box.unheard == 1


def test_a_plugin_listening_in_process_gets_messages_no_other_node_subscribes():
    box = Outbox()
    box.loopback_at_put = True
    got = []
    box.loopback = lambda topic, raw, msg_type: got.append(deserialize_message(raw, msg_type).data)
    box.listens = lambda topic: topic == '/fake'
    box.wrap(FakePublisher(subscribers=0)).publish(UInt32(data=4))
    box.stop()
    assert got == [4] and box.unheard == 0


def test_a_latched_topic_keeps_every_message_for_late_joiners():
    box = Outbox()
    pub = FakePublisher(subscribers=0, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    box.wrap(pub).publish(UInt32(data=9))
    box.stop()
    assert pub.published == [9] and box.unheard == 0


def test_a_latched_topic_keeps_its_last_message_for_later_plugin_subscribers():
    box = Outbox()
    latched = box.wrap(FakePublisher(subscribers=0, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    volatile = FakePublisher()
    volatile.topic_name = '/volatile'
    for i in (1, 2):
        latched.publish(UInt32(data=i))
        box.wrap(volatile).publish(UInt32(data=i))
    data, msg_type = box.last_latched('/fake')
    assert msg_type is UInt32 and deserialize_message(data, UInt32).data == 2
    assert box.last_latched('/volatile') is None


def test_a_message_handed_over_reaches_the_robot_as_it_is_and_dds_serialised():
    box = Outbox()
    pub = FakePublisher()
    got = []
    box.loopback = lambda topic, data, msg_type: got.append(data)
    msg = UInt32(data=3)
    box.wrap(pub, hand_over=True).publish(msg)
    assert got[0] is msg  # at once, no copy
    assert pub.published == []
    box.flush()
    assert pub.published == [3]  # serialised for DDS by the outbox


def test_is_heard_says_whether_anyone_would_get_a_message():
    box = Outbox()
    box.loopback = lambda topic, data, msg_type: None
    box.listens = lambda topic: False
    pub = FakePublisher(subscribers=0)
    assert not is_heard(pub) and not is_heard(box.wrap(pub))
    pub.subscribers = 1  # another node
    assert is_heard(pub) and is_heard(box.wrap(pub))
    latched = FakePublisher(subscribers=0, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    assert is_heard(latched) and is_heard(box.wrap(latched))
    box.listens = lambda topic: topic == '/fake'  # a plugin of the robot
    assert is_heard(box.wrap(FakePublisher(subscribers=0)))


def build_uint32(value, built_in):
    built_in.append(threading.current_thread().name)
    return UInt32(data=value)


def test_a_report_published_built_is_built_by_the_outbox_thread_and_reaches_robot_and_dds():
    box = Outbox('test-publish')
    pub = FakePublisher()
    got, built_in = [], []
    box.loopback = lambda topic, data, msg_type: got.append((data, msg_type))
    box.wrap(pub).publish_built(build_uint32, 7, built_in)
    assert built_in == [] and got == []  # the loop only queued it
    box.start()
    try:
        assert wait_until(lambda: pub.published == [7], 5.0)
    finally:
        box.stop()
    assert built_in == ['test-publish']
    ((msg, msg_type),) = got
    assert msg.data == 7 and msg_type is UInt32  # the object built, no serialised copy


def test_a_report_published_built_with_an_immediate_loopback_is_built_at_once():
    box = Outbox()
    box.loopback_at_put = True  # lockstep: the robot's subscribers get it in this tick
    got, built_in = [], []
    box.loopback = lambda topic, data, msg_type: got.append(data.data)
    box.listens = lambda topic: True
    box.wrap(FakePublisher(subscribers=0)).publish_built(build_uint32, 8, built_in)
    assert got == [8] and built_in == [threading.current_thread().name]
    box.stop()


def test_a_report_nobody_would_get_is_never_built_and_is_counted():
    box = Outbox()
    box.loopback = lambda topic, data, msg_type: pytest.fail('no plugin listens')
    box.listens = lambda topic: False
    built_in = []
    box.wrap(FakePublisher(subscribers=0)).publish_built(build_uint32, 1, built_in)
    box.stop()
    assert built_in == [] and box.unheard == 1


def test_a_failing_build_is_counted_and_logged_and_the_next_report_still_goes_out(caplog):
    box = Outbox()
    pub = FakePublisher()
    wrapped = box.wrap(pub)

    def broken():
        raise ValueError('bad report')

    for _ in range(3):
        wrapped.publish_built(broken)
    wrapped.publish_built(build_uint32, 2, [])
    box.stop()
    assert box.build_errors == 3 and pub.published == [2]
    # one line a second at most, with the count of those held back
    failures = [r for r in caplog.records if 'bad report' in r.getMessage()]
    assert len(failures) == 1 and '/fake' in failures[0].getMessage()


def test_publish_built_on_a_plain_publisher_builds_and_publishes_at_once():
    pub = FakePublisher()  # no outbox: rm_robot without a loop
    built_in = []
    publish_built(pub, build_uint32, 5, built_in)
    assert pub.published == [5] and built_in == [threading.current_thread().name]


def test_a_report_published_built_by_a_hand_over_publisher_reaches_the_robot_at_once():
    # A hand-over topic's plugins get its messages in the publishing tick: built reports too.
    box = Outbox()
    got, built_in = [], []
    box.loopback = lambda topic, data, msg_type: got.append(data.data)
    box.listens = lambda topic: True
    pub = FakePublisher()
    box.wrap(pub, hand_over=True).publish_built(build_uint32, 6, built_in)
    assert got == [6] and built_in == [threading.current_thread().name]
    box.flush()
    assert pub.published == [6]
