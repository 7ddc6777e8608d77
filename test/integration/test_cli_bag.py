"""rmcli bag record/play round trips through child processes (private domain).

A test node publishes a fixed schedule on two topics (one rm_msgs type, one std type)
while `rmcli bag record` runs; the bag must hold the same messages in the same order with
the same gaps, and `rmcli bag play` must give them back to a test subscriber the same way.

Timing tolerance: each message's time, less the original's (the recorded times less the
publish calls', the played times less the recorded ones), may spread over TIMING_TOLERANCE_S
(300 ms) across the schedule (1.15 s, gaps of 50-300 ms). On a quiet machine they agree
within a few ms; the margin is for the 2-vCPU VM under CPU steal or a parallel test run,
where the recorder or the subscriber can wait 100 ms for a core and then take two messages
at once: their gap shrinks to nothing, but neither is more than the wait late. A recorder
or player that lost the timing (every message at once, or at twice the rate) is 0.58 s or
more off.
"""

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import rclpy
import yaml
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.serialization import deserialize_message
from rosbags.highlevel import AnyReader
from std_msgs.msg import String
from support.ros import rclpy_context, start_process, stop_process, wait_until

from rm_msgs.msg import ChassisCmd

pytestmark = [pytest.mark.ros, pytest.mark.slow]

TIMEOUT_S = 30.0
TIMING_TOLERANCE_S = 0.3
CMD_TOPIC = '/cli_bag/chassis_cmd'
TEXT_TOPIC = '/cli_bag/chatter'
# (time from start [s], topic): gaps of 50..300 ms, alternating topics and not.
SCHEDULE = [
    (0.00, CMD_TOPIC),
    (0.10, TEXT_TOPIC),
    (0.35, CMD_TOPIC),
    (0.40, TEXT_TOPIC),
    (0.70, CMD_TOPIC),
    (0.75, CMD_TOPIC),
    (1.00, TEXT_TOPIC),
    (1.15, CMD_TOPIC),
]
TYPES = {CMD_TOPIC: ChassisCmd, TEXT_TOPIC: String}


def rmcli(*args):
    return start_process([sys.executable, '-m', 'rm_bringup.cli', *args])


def rmcli_run(*args):
    """rmcli run to its end: its exit code and output."""
    return subprocess.run([sys.executable, '-m', 'rm_bringup.cli', *args], check=False,
                          capture_output=True, text=True, timeout=TIMEOUT_S)


def schedule_message(index, topic):
    if topic == CMD_TOPIC:
        msg = ChassisCmd(mode=index % 5, power_limit=10.0 * index, follow_source=f'cmd{index}')
        msg.header.stamp.sec = 1000 + index
        return msg
    return String(data=f'text {index}')


def timing_spread(times, originals):
    """How far apart the messages' delays are [s] (0: every gap kept exactly)."""
    delays = [t - o for t, o in zip(times, originals, strict=True)]
    return max(delays) - min(delays)


class Graph:
    """A node with an executor in its own context, spun while waiting."""

    def __init__(self, context):
        self.node = rclpy.create_node('cli_bag_test', context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)

    def wait(self, predicate, timeout=TIMEOUT_S):
        return wait_until(predicate, timeout, spin=self.executor.spin_once)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()


def record_schedule(bag: Path, storage: str) -> dict:
    """Record SCHEDULE with `rmcli bag record`; return what was published and learnt."""
    with rclpy_context() as context:
        graph = Graph(context)
        try:
            publishers = {t: graph.node.create_publisher(TYPES[t], t, 10) for t in TYPES}
            # Publishers first: a recorder that starts later discovers them at once.
            recorder = rmcli('bag', 'record', CMD_TOPIC, TEXT_TOPIC, '-o', str(bag), '-s', storage)
            try:
                subscribed = graph.wait(
                    lambda: all(p.get_subscription_count() > 0 for p in publishers.values())
                )
                assert subscribed, 'the recorder never subscribed'
                sent, sent_at = [], []
                start = time.monotonic()
                for index, (due, topic) in enumerate(SCHEDULE):
                    time.sleep(max(0.0, start + due - time.monotonic()))  # keep the schedule
                    msg = schedule_message(index, topic)
                    publishers[topic].publish(msg)
                    sent_at.append(time.monotonic())
                    sent.append((topic, msg))
                for publisher in publishers.values():
                    assert publisher.wait_for_all_acked(Duration(seconds=TIMEOUT_S))
                hashes = {
                    t: str(graph.node.get_publishers_info_by_topic(t)[0].topic_type_hash)
                    for t in TYPES
                }
            finally:
                out, err = stop_process(recorder)
            assert recorder.returncode == 0, f'{out}\n{err}'
            assert f'Recording stopped: {len(SCHEDULE)} messages on 2 topics' in out, out + err
        finally:
            graph.close()
    return {'bag': bag, 'sent': sent, 'sent_at': sent_at, 'hashes': hashes}


def read_bag(bag: Path):
    """(topic, rclpy message, timestamp [s]) in bag order, decoded with rclpy."""
    with AnyReader([bag]) as reader:
        return [
            (conn.topic, deserialize_message(bytes(raw), TYPES[conn.topic]), stamp * 1e-9)
            for conn, stamp, raw in reader.messages()
        ]


def play(bag: Path, *options, topics=None) -> list:
    """Play bag into test subscribers of topics (TYPES by default): (time the player sent
    it [s], topic, msg), in the order sent.

    The player's send times (DDS source timestamps), not this process's: after it lost the
    CPU, this process takes all queued messages of one topic before the other's.
    """
    received = []

    def keep(topic):
        return lambda msg, info: received.append((info['source_timestamp'] * 1e-9, topic, msg))

    with rclpy_context() as context:
        graph = Graph(context)
        try:
            for topic, cls in (topics or TYPES).items():
                graph.node.create_subscription(cls, topic, keep(topic), 10)
            # The subscribers exist, so the wait ends when discovery has matched them.
            player = rmcli(
                'bag', 'play', str(bag), '--wait-for-subscribers', str(TIMEOUT_S), *options
            )
            try:
                graph.wait(lambda: len(received) >= len(SCHEDULE) or player.poll() is not None)
                graph.wait(lambda: len(received) >= len(SCHEDULE), timeout=2.0)
            finally:
                out, err = (
                    stop_process(player, timeout=TIMEOUT_S)
                    if player.poll() is None
                    else player.communicate()
                )
            assert player.returncode == 0, f'{out}\n{err}'
        finally:
            graph.close()
    return sorted(received, key=lambda r: r[0])


@pytest.fixture(scope='module')
def recording(tmp_path_factory):
    return record_schedule(tmp_path_factory.mktemp('cli_bag') / 'bag', 'mcap')


def test_record_keeps_every_message_in_order_with_its_timing(recording):
    recorded = read_bag(recording['bag'])
    assert [(topic, msg) for topic, msg, _ in recorded] == recording['sent']
    recorded_at = [t for _, _, t in recorded]
    assert timing_spread(recorded_at, recording['sent_at']) <= TIMING_TOLERANCE_S


def test_recorded_bag_has_type_hashes_and_offered_qos(recording):
    metadata = yaml.safe_load((recording['bag'] / 'metadata.yaml').read_text())
    info = metadata['rosbag2_bagfile_information']
    assert info['storage_identifier'] == 'mcap'
    topics = {t['topic_metadata']['name']: t for t in info['topics_with_message_count']}
    for topic in TYPES:
        meta = topics[topic]['topic_metadata']
        # The hash rosbags computed from the installed .msg is the publisher's own.
        assert meta['type_description_hash'] == recording['hashes'][topic]
        assert meta['offered_qos_profiles'][0]['reliability'] == 'reliable'
        assert meta['offered_qos_profiles'][0]['durability'] == 'volatile'
    assert topics[CMD_TOPIC]['topic_metadata']['type'] == 'rm_msgs/msg/ChassisCmd'
    assert topics[CMD_TOPIC]['message_count'] == sum(t == CMD_TOPIC for _, t in SCHEDULE)


def test_play_gives_back_the_same_messages_in_order_with_their_timing(recording):
    received = play(recording['bag'])
    assert [(topic, msg) for _, topic, msg in received] == recording['sent']
    recorded_at = [t for _, _, t in read_bag(recording['bag'])]
    assert timing_spread([t for t, _, _ in received], recorded_at) <= TIMING_TOLERANCE_S


def test_play_at_rate_2_halves_the_duration(recording):
    received = play(recording['bag'], '--rate', '2')
    assert [(topic, msg) for _, topic, msg in received] == recording['sent']
    recorded = read_bag(recording['bag'])
    recorded_span = recorded[-1][2] - recorded[0][2]  # ~1.15 s
    played_span = received[-1][0] - received[0][0]
    # Half of ~1.15 s is ~0.58 s; 1x playback (~1.15 s) would be ~0.58 s off, far outside.
    assert played_span == pytest.approx(recorded_span / 2, abs=TIMING_TOLERANCE_S)


def test_sqlite3_storage_records_and_plays_back(tmp_path):
    recording = record_schedule(tmp_path / 'bag', 'sqlite3')
    assert (tmp_path / 'bag' / 'bag.db3').is_file()
    received = play(recording['bag'])
    assert [(topic, msg) for _, topic, msg in received] == recording['sent']


def test_record_stops_on_sigterm_with_a_readable_bag(tmp_path):
    # SIGTERM (how launch stops a process) closes the bag like SIGINT does.
    recorder = rmcli('bag', 'record', '-a', '-o', str(tmp_path / 'bag'))
    try:
        wait_until((tmp_path / 'bag').exists, TIMEOUT_S)
    finally:
        recorder.send_signal(signal.SIGTERM)
        out, err = recorder.communicate(timeout=TIMEOUT_S)
    assert recorder.returncode == 0, err
    assert 'Recording stopped' in out
    # rosbags writes metadata.yaml only when the bag is closed.
    assert (tmp_path / 'bag' / 'metadata.yaml').is_file()
    with AnyReader([tmp_path / 'bag']) as reader:
        # The counts in metadata.yaml agree with what the storage file holds.
        assert reader.message_count == sum(1 for _ in reader.messages())


def test_play_remaps_a_recorded_topic_onto_another(recording):
    remapped = '/cli_bag/remapped_cmd'
    received = play(
        recording['bag'], '--remap', f'{CMD_TOPIC}:={remapped}',
        topics={remapped: ChassisCmd, TEXT_TOPIC: String},
    )
    expected = [(remapped if t == CMD_TOPIC else t, msg) for t, msg in recording['sent']]
    assert [(topic, msg) for _, topic, msg in received] == expected



def test_play_onto_a_topic_of_another_type_says_its_subscribers_get_nothing(recording):
    # the commands remapped onto a topic the robot takes as another type: DDS drops them all
    wrong = '/cli_bag/typed_otherwise'
    with rclpy_context() as context:
        graph = Graph(context)
        try:
            got = []
            graph.node.create_subscription(String, wrong, got.append, 10)
            graph.node.create_subscription(String, TEXT_TOPIC, lambda msg: None, 10)
            player = rmcli('bag', 'play', str(recording['bag']), '--remap',
                           f'{CMD_TOPIC}:={wrong}', '--wait-for-subscribers', '3', '-r', '4')
            graph.wait(lambda: player.poll() is not None)
            out, err = player.communicate(timeout=TIMEOUT_S)
        finally:
            graph.close()
    assert player.returncode == 0, out + err
    assert (f'rmcli: warning: {wrong} is subscribed as std_msgs/msg/String (/cli_bag_test), '
            'not as rm_msgs/msg/ChassisCmd: those subscribers never get these messages') in err
    assert err.count('rmcli: warning:') == 1, err  # the text topic matched: not named
    assert not got


def test_play_with_clock_publishes_the_bag_time_while_it_plays(recording):
    # --clock 50: the bag's time on /clock every 20 ms of playback, between messages too
    from rosgraph_msgs.msg import Clock

    recorded = read_bag(recording['bag'])
    first, last = recorded[0][2], recorded[-1][2]
    # (when the player sent it [ns], kind, clock): ordered by the player's send time, since
    # this process takes the two topics' messages in its own order (all of a queued topic
    # first, after it lost the CPU)
    arrivals: list[tuple[int, str, float]] = []
    with rclpy_context() as context:
        graph = Graph(context)
        try:
            graph.node.create_subscription(
                Clock, '/clock',
                lambda m, info: arrivals.append(
                    (info['source_timestamp'], 'clock', m.clock.sec + m.clock.nanosec * 1e-9)
                ),
                100,
            )
            graph.node.create_subscription(
                ChassisCmd, CMD_TOPIC,
                lambda m, info: arrivals.append((info['source_timestamp'], 'cmd', 0.0)), 10)
            player = rmcli('bag', 'play', str(recording['bag']), '--clock', '50',
                           '--topics', CMD_TOPIC, '--wait-for-subscribers', str(TIMEOUT_S))
            try:
                graph.wait(lambda: player.poll() is not None)
                graph.wait(lambda: False, timeout=0.2)  # the last messages in flight
            finally:
                out, err = (stop_process(player, timeout=TIMEOUT_S) if player.poll() is None
                            else player.communicate())
            assert player.returncode == 0, f'{out}\n{err}'
        finally:
            graph.close()
    arrivals = [(kind, t) for _, kind, t in sorted(arrivals)]
    clocks = [t for kind, t in arrivals if kind == 'clock']
    # ~1.15 s at 50 Hz is ~58 ticks; generous for a loaded machine
    assert len(clocks) >= 20, clocks
    assert clocks == sorted(clocks)
    assert first - 0.001 <= clocks[0] and clocks[-1] <= last + 0.1
    # each command was sent with the clock at about its recording time: the tick sent last
    # before it, or (the first command) the one right after it
    cmd_times = [t for topic, _, t in recorded if topic == CMD_TOPIC]
    at_arrival = []
    for i, (kind, _) in enumerate(arrivals):
        if kind == 'cmd':
            before = [t for k, t in arrivals[:i] if k == 'clock']
            after = [t for k, t in arrivals[i:] if k == 'clock']
            at_arrival.append(before[-1] if before else after[0])
    assert len(at_arrival) == len(cmd_times)
    for clock_then, stamp in zip(at_arrival, cmd_times, strict=True):
        assert abs(clock_then - stamp) < 0.1, (clock_then, stamp)


def test_play_rebuilds_a_topic_recorded_with_an_older_definition(tmp_path):
    # A ChassisCmd recorded before speed_gear existed (and with a field since removed).
    from rm_bringup.cli.bag_convert import message_with_defaults
    from rm_bringup.cli.bag_types import msg_file
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    msgtype = 'rm_msgs/msg/ChassisCmd'
    text = msg_file(msgtype).read_text(encoding='utf-8')
    old = text.replace('uint8 speed_gear', 'float64 legacy_gain')
    assert old != text
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg(old, msgtype))
    bag = tmp_path / 'old'
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection(CMD_TOPIC, msgtype, typestore=store)
        for i in range(3):
            msg = message_with_defaults(store, msgtype, mode=ChassisCmd.GYRO, power_limit=40.0 + i)
            writer.write(connection, 1_000_000_000 + i * 20_000_000,
                         store.serialize_cdr(msg, msgtype))
    received = []
    with rclpy_context() as context:
        graph = Graph(context)
        try:
            graph.node.create_subscription(ChassisCmd, CMD_TOPIC, received.append, 10)
            player = rmcli('bag', 'play', str(bag), '--wait-for-subscribers', str(TIMEOUT_S))
            try:
                graph.wait(lambda: len(received) >= 3 or player.poll() is not None)
                graph.wait(lambda: len(received) >= 3, timeout=2.0)
            finally:
                out, err = stop_process(player, timeout=TIMEOUT_S)
        finally:
            graph.close()
    assert player.returncode == 0, f'{out}\n{err}'
    assert [(m.mode, m.power_limit, m.speed_gear) for m in received] == [
        (ChassisCmd.GYRO, 40.0 + i, ChassisCmd.GEAR_NORMAL) for i in range(3)
    ]
    assert 'new fields at their defaults: speed_gear' in err
    assert 'not played: legacy_gain' in err


def test_a_recording_killed_mid_write_is_made_readable_by_reindex(tmp_path):
    # The finding: a bag being recorded when `rmcli bag record` was killed (-9) could not
    # be read at all (5.4 MB on disk, no metadata.yaml).
    bag = tmp_path / 'bag'
    payload = 'x' * 1000
    with rclpy_context() as context:
        graph = Graph(context)
        try:
            publisher = graph.node.create_publisher(String, TEXT_TOPIC, 100)
            recorder = rmcli('bag', 'record', TEXT_TOPIC, '-o', str(bag))
            try:
                assert graph.wait(lambda: publisher.get_subscription_count() > 0)
                for index in range(3000):  # ~3 MB: whole 1 MiB chunks, and one being filled
                    publisher.publish(String(data=f'{index} {payload}'))
                    time.sleep(0.0005)
                time.sleep(1.0)  # the recorder takes what is on its way
            finally:
                recorder.kill()
                recorder.communicate(timeout=TIMEOUT_S)
        finally:
            graph.close()
    assert not (bag / 'metadata.yaml').exists()
    info = rmcli_run('bag', 'info', str(bag))
    assert info.returncode == 1 and f'rmcli bag reindex {bag}' in info.stderr, info.stderr
    fixed = rmcli_run('bag', 'reindex', str(bag))
    assert fixed.returncode == 0, fixed.stderr
    assert 'closed after its last whole record' in fixed.stdout, fixed.stdout
    with AnyReader([bag]) as reader:
        got = [reader.deserialize(raw, conn.msgtype).data
               for conn, _, raw in reader.messages()]
    assert len(got) >= 1000  # at least the chunks written before the kill
    indices = [int(text.split()[0]) for text in got]
    assert indices == sorted(indices)  # in order
    assert got == [f'{i} {payload}' for i in indices]  # each message whole
    again = rmcli_run('bag', 'info', str(bag))
    assert again.returncode == 0 and f'Count: {len(got)}' in again.stdout, again.stderr


def test_play_with_restamp_stamps_each_command_with_the_time_it_is_sent(recording):
    # The finding: replayed commands kept their recorded stamps, and the robot refused them
    # as stale ("stamp is 168.650 s old").
    received = play(recording['bag'], '--restamp')
    assert [(topic, type(msg)) for _, topic, msg in received] == [
        (topic, type(msg)) for topic, msg in recording['sent']]
    for sent_at, topic, msg in received:
        if topic == CMD_TOPIC:
            stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
            assert abs(stamp - sent_at) < 0.5, (stamp, sent_at)  # was 1000 + index s
            assert msg.follow_source.startswith('cmd')  # the rest as recorded
