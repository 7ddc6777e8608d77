"""Outbox: messages from the loop published by the edge's thread, in order, never blocking."""

import threading

from rm_base.plugin.outbox import Outbox
from support.ros import wait_until


class FakePublisher:
    topic_name = '/fake'

    def __init__(self):
        self.published = []
        self.threads = set()

    def publish(self, msg):
        self.published.append(msg)
        self.threads.add(threading.current_thread().name)


def test_messages_are_published_in_order_by_the_outbox_thread():
    box = Outbox('test-publish')
    pub = FakePublisher()
    wrapped = box.wrap(pub)
    box.start()
    try:
        for i in range(100):
            wrapped.publish(i)
        assert wait_until(lambda: len(pub.published) == 100, 5.0)
    finally:
        box.stop()
    assert pub.published == list(range(100))
    assert pub.threads == {'test-publish'}


def test_stop_publishes_what_is_still_queued():
    box = Outbox()
    pub = FakePublisher()
    box.wrap(pub).publish('last words')  # never started: stop() flushes
    box.stop()
    assert pub.published == ['last words']


def test_when_the_edge_falls_behind_expect_the_oldest_dropped_and_counted():
    box = Outbox(max_queued=3)
    pub = FakePublisher()
    wrapped = box.wrap(pub)
    for i in range(5):
        wrapped.publish(i)
    box.stop()
    assert pub.published == [2, 3, 4]
    assert box.dropped == 2
