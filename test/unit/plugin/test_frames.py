"""FramePublisher: the tree takes a link at once; /tf's message is built by the edge."""

import threading

import pytest
from rclpy.qos import QoSProfile
from rm_base.geometry.frame_tree import FrameTree
from rm_base.geometry.transforms import SE3
from rm_base.plugin import frames as frames_module
from rm_base.plugin.frames import FramePublisher
from rm_base.plugin.outbox import Outbox
from support.ros import wait_until

STAMP_NS = 1_700_000_000_250_000_000


class FakeTfPublisher:
    topic_name = '/tf'
    qos_profile = QoSProfile(depth=100)

    def __init__(self, subscribers=1):
        self.subscribers = subscribers
        self.published = []
        self.threads = set()

    def get_subscription_count(self):
        return self.subscribers

    def publish(self, msg):
        self.published.append(msg)
        self.threads.add(threading.current_thread().name)


@pytest.fixture
def edge():
    box = Outbox('test-edge')
    yield box
    box.stop()


def test_the_tree_has_the_link_at_once_and_the_edge_thread_builds_tf(edge, monkeypatch):
    built_in = []
    build = frames_module.transform_message

    def noted(*args):
        built_in.append(threading.current_thread().name)
        return build(*args)

    monkeypatch.setattr(frames_module, 'transform_message', noted)
    tree, pub = FrameTree(), FakeTfPublisher()
    frames = FramePublisher(tree, edge.wrap(pub, hand_over=True), static=False)
    base = SE3.from_translation_rpy((1.0, 2.0, 0.0), 0.0, 0.0, 0.5)
    frames.send([('odom', 'base_link', base)], STAMP_NS)
    assert tree.lookup('odom', 'base_link').transform.translation == pytest.approx((1, 2, 0))
    assert pub.published == [] and built_in == []  # the loop only queued it
    edge.start()
    assert wait_until(lambda: len(pub.published) == 1, 5.0)
    assert pub.threads == {'test-edge'} and built_in == ['test-edge']
    (msg,) = pub.published
    (link,) = msg.transforms
    assert (link.header.frame_id, link.child_frame_id) == ('odom', 'base_link')
    assert (link.header.stamp.sec, link.header.stamp.nanosec) == (1_700_000_000, 250_000_000)
    assert (link.transform.translation.x, link.transform.translation.y) == (1.0, 2.0)
    assert link.transform.rotation.z == pytest.approx(0.2474, abs=1e-4)  # sin(0.25)


def test_tf_nobody_would_get_is_never_built(edge, monkeypatch):
    built = []
    monkeypatch.setattr(frames_module, 'tf_message', lambda *args: built.append(args))
    tree, pub = FrameTree(), FakeTfPublisher(subscribers=0)
    frames = FramePublisher(tree, edge.wrap(pub, hand_over=True), static=False)
    frames.send([('odom', 'base_link', SE3.identity())], STAMP_NS)
    edge.start()
    edge.flush()
    assert pub.published == [] and built == []
    assert tree.lookup('odom', 'base_link').transform.translation == pytest.approx((0, 0, 0))
