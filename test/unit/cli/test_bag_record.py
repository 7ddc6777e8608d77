"""bag record: topic selection (rosbag2's rules) and the recorder, with a stand-in node."""

import re
import threading
import time
import types

import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from rm_bringup.cli.bag_record import Recorder, TopicSelection, record, selection_from_args
from rm_bringup.cli.bag_types import BagTypes
from rm_bringup.cli.errors import UsageError
from rm_bringup.cli.main import build_parser
from rosbags.highlevel import AnyReader
from rosbags.interfaces import QosReliability
from rosbags.rosbag2 import StoragePlugin, Writer

from rm_msgs.msg import ChassisCmd


def selection(*argv):
    return selection_from_args(build_parser().parse_args(['bag', 'record', *argv]))


def test_listed_topics_only_and_names_made_absolute():
    chosen = selection('chassis_cmd', '--topics', '/odom')
    assert chosen.wants('/chassis_cmd') and chosen.wants('/odom')
    assert not chosen.wants('/rosout')


def test_all_skips_hidden_topics_unless_asked():
    assert selection('-a').wants('/rosout')
    assert not selection('-a').wants('/_internal/x')
    assert selection('-a', '--include-hidden-topics').wants('/_internal/x')


def test_regex_matches_anywhere_in_the_name_and_exclusions_win():
    chosen = selection('-e', 'cmd', '--exclude-regex', '^/gimbal', '--exclude-topics', '/shoot_cmd')
    assert chosen.wants('/chassis_cmd')
    assert not chosen.wants('/gimbal_cmd')
    assert not chosen.wants('/shoot_cmd')
    assert not chosen.wants('/odom')


def test_explicit_topic_is_recorded_even_if_hidden():
    assert TopicSelection(topics=frozenset({'/_x'})).wants('/_x')


def test_exclusion_needs_all_or_regex():
    with pytest.raises(UsageError, match='need --all'):
        selection('/odom', '--exclude-regex', 'x')


def test_bad_regex_is_a_usage_error():
    with pytest.raises(UsageError, match=re.escape("invalid regular expression '(")):
        selection('-e', '(')


# --- the recorder with a stand-in node (no ROS) ----------------------------------------------


class FakeClock:
    def __init__(self):
        self.ns = 5_000_000_000

    def now(self):
        self.ns += 10_000_000  # each message 10 ms after the previous one
        return types.SimpleNamespace(nanoseconds=self.ns)


class FakeNode:
    """The graph as the recorder sees it: topics, their publishers' QoS, subscriptions made."""

    def __init__(self, graph, offers):
        self.graph, self.offers, self.subscriptions = graph, offers, []
        self.clock = FakeClock()

    def get_topic_names_and_types(self):
        return self.graph

    def get_publishers_info_by_topic(self, topic):
        return [
            types.SimpleNamespace(qos_profile=q, topic_type_hash='', node_name='pub')
            for q in self.offers.get(topic, [])
        ]

    def create_subscription(self, msg_class, topic, callback, qos, raw=False):
        self.subscriptions.append(
            types.SimpleNamespace(cls=msg_class, topic=topic, callback=callback, qos=qos, raw=raw)
        )

    def get_clock(self):
        return self.clock


RELIABLE = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
BEST_EFFORT = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


@pytest.fixture
def bag_writer(tmp_path):
    writer = Writer(tmp_path / 'bag', version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    return writer


def test_recorder_subscribes_raw_to_published_selected_topics(bag_writer, capsys):
    node = FakeNode(
        graph=[
            ('/chassis_cmd', ['rm_msgs/msg/ChassisCmd']),
            ('/odom', ['nav_msgs/msg/Odometry']),  # no publisher yet
            ('/mixed', ['std_msgs/msg/String', 'std_msgs/msg/Int32']),
            ('/not_selected', ['std_msgs/msg/String']),
        ],
        offers={'/chassis_cmd': [RELIABLE, RELIABLE], '/mixed': [RELIABLE]},
    )
    recorder = Recorder(node, bag_writer, BagTypes(), selection('/chassis_cmd', '/odom', '/mixed'))
    recorder.discover()
    assert [(s.topic, s.cls, s.raw) for s in node.subscriptions] == [
        ('/chassis_cmd', ChassisCmd, True)
    ]
    # Both publishers offer RELIABLE, so the recorder asks for it (rosbag2's rule).
    assert node.subscriptions[0].qos.reliability == ReliabilityPolicy.RELIABLE
    assert 'not recording /mixed: it has more than one type' in capsys.readouterr().err
    # /odom is subscribed once a publisher shows up; the others are not tried again.
    node.offers['/odom'] = [BEST_EFFORT]
    recorder.discover()
    assert [s.topic for s in node.subscriptions] == ['/chassis_cmd', '/odom']
    assert node.subscriptions[1].qos.reliability == ReliabilityPolicy.BEST_EFFORT


def test_recorder_writes_raw_data_with_receive_time_and_offered_qos(bag_writer):
    node = FakeNode([('/chassis_cmd', ['rm_msgs/msg/ChassisCmd'])], {'/chassis_cmd': [RELIABLE]})
    recorder = Recorder(node, bag_writer, BagTypes(), selection('/chassis_cmd'))
    recorder.discover()
    sent = [ChassisCmd(mode=m) for m in (1, 4)]
    for msg in sent:
        node.subscriptions[0].callback(serialize_message(msg))
    bag_writer.close()
    assert recorder.counts == {'/chassis_cmd': 2}
    with AnyReader([bag_writer.path]) as reader:
        (connection,) = reader.connections
        assert connection.ext.offered_qos_profiles[0].reliability == QosReliability.RELIABLE
        got = [
            (stamp, deserialize_message(bytes(raw), ChassisCmd))
            for _, stamp, raw in reader.messages()
        ]
    # FakeClock: 5.01 s then 5.02 s
    assert got == [(5_010_000_000, sent[0]), (5_020_000_000, sent[1])]


def test_topic_of_an_unknown_type_is_skipped_with_a_warning(bag_writer, capsys):
    node = FakeNode([('/x', ['no_such_msgs/msg/Thing'])], {'/x': [RELIABLE]})
    recorder = Recorder(node, bag_writer, BagTypes(), selection('/x'))
    recorder.discover()
    recorder.discover()
    assert node.subscriptions == []
    assert capsys.readouterr().err.count('not recording /x') == 1


class CountingRecorder:
    def __init__(self):
        self.discoveries = 0
        self.counts = {}

    def discover(self):
        self.discoveries += 1


class StoppingExecutor:
    """Sets stop after a number of spins, like a Ctrl-C during the recording."""

    def __init__(self, stop, spins):
        self.stop, self.spins = stop, spins

    def spin_once(self, timeout_sec):
        self.spins -= 1
        if self.spins <= 0:
            self.stop.set()
        time.sleep(0.001)


def test_no_discovery_looks_for_topics_at_the_start_only():
    stop = threading.Event()
    recorder = CountingRecorder()
    record(StoppingExecutor(stop, spins=20), recorder, stop, poll_period_s=None)
    assert recorder.discoveries == 1


def test_discovery_repeats_every_polling_period():
    stop = threading.Event()
    recorder = CountingRecorder()
    record(StoppingExecutor(stop, spins=20), recorder, stop, poll_period_s=1e-6)
    assert recorder.discoveries > 10
