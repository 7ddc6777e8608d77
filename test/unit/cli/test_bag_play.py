"""Broken bags: one clear line naming the file, exit 1, before any ROS node starts."""

import threading
import time

import pytest
from rclpy.serialization import deserialize_message
from rm_bringup.cli.bag_io import open_bag
from rm_bringup.cli.bag_play import PlayOptions, play
from rm_bringup.cli.bag_topics import parse_remaps
from rm_bringup.cli.errors import BagError, CliError
from rm_bringup.cli.main import main
from std_msgs.msg import String

S = 1_000_000_000


@pytest.fixture
def good_bag(write_bag, make):
    return write_bag(
        [
            (
                '/chatter',
                'std_msgs/msg/String',
                S + i * S // 100,
                make('std_msgs/msg/String', data='x' * 40),
            )
            for i in range(200)
        ]
    )


def error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert 'Traceback' not in err[0]
    return err[0]


def test_truncated_mcap_is_one_clear_line_naming_the_file(good_bag, capsys):
    data_file = good_bag / f'{good_bag.name}.mcap'
    data_file.write_bytes(data_file.read_bytes()[: data_file.stat().st_size // 2])
    assert main(['bag', 'play', str(good_bag)]) == 1
    line = error_line(capsys)
    assert line.startswith('rmcli: error: cannot read bag')
    assert str(data_file) in line
    assert 'truncated' in line
    # the line names the command that mends it, and that command does
    assert line.endswith(f'rmcli bag reindex {good_bag}')
    assert main(['bag', 'reindex', str(good_bag)]) == 0
    capsys.readouterr()
    assert main(['bag', 'info', str(good_bag)]) == 0


def test_garbage_inside_an_mcap_is_one_clear_line(write_bag, make, tmp_path, capsys):
    # This damage only shows while reading the messages (rosbags raises OverflowError), so
    # it is read through `bag plot`, which reads every message without starting ROS.
    gimbal = make('rm_msgs/msg/GimbalState', reason='x' * 40)
    bag = write_bag(
        [('/g', 'rm_msgs/msg/GimbalState', S + i * S // 100, gimbal) for i in range(200)]
    )
    data_file = bag / f'{bag.name}.mcap'
    data = bytearray(data_file.read_bytes())
    third = len(data) // 3
    data[third : third + 2000] = b'\xff' * 2000
    data_file.write_bytes(bytes(data))
    assert main(['bag', 'plot', str(bag), '-o', str(tmp_path / 'plots')]) == 1
    assert str(data_file) in error_line(capsys)


def test_corrupted_sqlite3_bag_is_one_clear_line(write_bag, make, capsys):
    bag = write_bag(
        [('/chatter', 'std_msgs/msg/String', S, make('std_msgs/msg/String', data='a'))],
        storage='sqlite3',
    )
    db = bag / f'{bag.name}.db3'
    db.write_bytes(b'not a database' * 100)
    assert main(['bag', 'play', str(bag)]) == 1
    assert str(db) in error_line(capsys)


def test_missing_bag_and_folder_without_metadata(tmp_path, capsys):
    assert main(['bag', 'play', str(tmp_path / 'nothing')]) == 1
    assert 'does not exist' in error_line(capsys)
    assert main(['bag', 'play', str(tmp_path)]) == 1
    assert 'no metadata.yaml' in error_line(capsys)


def test_topics_not_in_the_bag_are_an_error_listing_what_is(good_bag, capsys):
    assert main(['bag', 'play', str(good_bag), '--topics', '/odom']) == 1
    line = error_line(capsys)
    assert '/odom' in line and '/chatter' in line


def test_damage_found_while_reading_is_a_bag_error(tmp_path):
    # rosbags may only hit damaged chunks while iterating; read_messages wraps that too.
    from rm_bringup.cli.bag_io import read_messages

    class DamagedReader:
        def messages(self, connections=(), start=None):
            yield ('connection', 1, b'ok')
            raise OverflowError('Python int too large to convert to C ssize_t')

    got = []
    with pytest.raises(BagError, match=r'cannot read bag .*bag: Python int too large'):
        for item in read_messages(DamagedReader(), tmp_path / 'bag'):
            got.append(item)
    assert got == [('connection', 1, b'ok')]


# --- the playback loop, with stand-in publishers (no ROS) ------------------------------------


class FakePublisher:
    """Collects what would be published; sets stop after stop_after messages."""

    def __init__(self, sent, stop, stop_after):
        self._sent, self._stop, self._stop_after = sent, stop, stop_after

    def publish(self, data):
        self._sent.append((time.monotonic(), deserialize_message(data, String).data))
        if len(self._sent) >= self._stop_after:
            self._stop.set()


@pytest.fixture
def five_messages(write_bag, make):
    # 'm0'..'m4', 40 ms apart
    return write_bag(
        [
            (
                '/chatter',
                'std_msgs/msg/String',
                S + i * 40_000_000,
                make('std_msgs/msg/String', data=f'm{i}'),
            )
            for i in range(5)
        ]
    )


def played(bag, stop_after=100, preset_stop=False, **options):
    sent = []
    stop = threading.Event()
    if preset_stop:
        stop.set()
    with open_bag(bag) as reader:
        publishers = {'/chatter': FakePublisher(sent, stop, stop_after)}
        start = time.monotonic()
        count = play(
            reader, bag, reader.connections, publishers, options=PlayOptions(**options), stop=stop
        )
    assert count == len(sent)
    return start, sent


def test_play_sends_every_message_once_in_order(five_messages):
    _, sent = played(five_messages)
    assert [data for _, data in sent] == ['m0', 'm1', 'm2', 'm3', 'm4']


def test_start_offset_skips_the_beginning_of_the_bag(five_messages):
    # offset 0.1 s: messages at 120 and 160 ms remain
    _, sent = played(five_messages, start_offset_s=0.1)
    assert [data for _, data in sent] == ['m3', 'm4']


def test_loop_starts_over_until_stopped(five_messages):
    _, sent = played(five_messages, loop=True, rate=4.0, stop_after=7)
    assert [data for _, data in sent] == ['m0', 'm1', 'm2', 'm3', 'm4', 'm0', 'm1']


def test_delay_waits_before_playing(five_messages):
    start, sent = played(five_messages, delay_s=0.2)
    assert sent[0][0] - start >= 0.2


def test_stop_ends_playback_at_once(five_messages):
    _, sent = played(five_messages, preset_stop=True)
    assert sent == []


# --- --remap ---------------------------------------------------------------------------------


def test_remaps_are_absolute_topic_pairs():
    assert parse_remaps(['/cmd_vel:=/vel_cmd', 'turtle1/cmd_vel:=vel_cmd']) == {
        '/cmd_vel': '/vel_cmd',
        '/turtle1/cmd_vel': '/vel_cmd',
    }


@pytest.mark.parametrize(
    ('items', 'match'),
    [
        (['/cmd_vel=/vel_cmd'], 'write FROM:=TO'),
        ([':=/vel_cmd'], 'write FROM:=TO'),
        (['/cmd_vel:='], 'write FROM:=TO'),
        (['/a:=/b', '/a:=/c'], '/a is remapped twice'),
    ],
)
def test_a_malformed_remap_is_one_clear_error(items, match):
    with pytest.raises(CliError, match=match):
        parse_remaps(items)


def test_remapping_two_types_onto_one_topic_is_refused_before_ros_starts(write_bag, make, capsys):
    bag = write_bag([
        ('/a', 'std_msgs/msg/String', S, make('std_msgs/msg/String', data='x')),
        ('/b', 'geometry_msgs/msg/Twist', S, make('geometry_msgs/msg/Twist')),
    ])
    assert main(['bag', 'play', str(bag), '--remap', '/a:=/b']) == 1
    assert 'would both be published on /b' in error_line(capsys)


# --- --clock -----------------------------------------------------------------------------------


class FakeClock:
    period_ns = 10_000_000  # 100 Hz

    def __init__(self, sent):
        self.sent = sent

    def publish(self, bag_ns):
        self.sent.append((time.monotonic(), 'clock', bag_ns))


def test_with_a_clock_the_bag_time_goes_out_between_messages_and_keeps_up_with_them(
    five_messages
):
    sent = []
    stop = threading.Event()
    with open_bag(five_messages) as reader:
        publishers = {'/chatter': FakePublisher(sent, stop, 100)}
        play(reader, five_messages, reader.connections, publishers,
             options=PlayOptions(rate=2.0), stop=stop, clock=FakeClock(sent))
    clocks = [entry[2] for entry in sent if len(entry) == 3]
    assert clocks == sorted(clocks) and S <= clocks[0] < S + 5_000_000
    assert len(clocks) >= 5  # 80 ms of playback at 100 Hz (wall-time: a loose bound)
    # the message i (recorded at S + 40 ms * i) goes out when the clock has reached it
    last_clock = None
    for entry in sent:
        if len(entry) == 3:
            last_clock = entry[2]
        else:
            index = int(entry[1][1])
            assert last_clock >= S + index * 40_000_000
