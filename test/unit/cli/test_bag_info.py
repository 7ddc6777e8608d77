"""bag info on bags written by the test."""

from rm_bringup.cli.bag_info import describe, format_size
from rm_bringup.cli.main import main

S = 1_000_000_000  # ns


def two_topic_bag(write_bag, make, storage='mcap'):
    samples = [
        (
            '/chassis_cmd',
            'rm_msgs/msg/ChassisCmd',
            10 * S + i * S // 10,
            make('rm_msgs/msg/ChassisCmd', mode=i),
        )
        for i in range(3)
    ]
    samples += [
        (
            '/chatter',
            'std_msgs/msg/String',
            10 * S + 250_000_000,
            make('std_msgs/msg/String', data='hi'),
        )
    ]
    return write_bag(samples, storage=storage)


def value(lines, key):
    return next(line for line in lines if line.startswith(key)).split(':', 1)[1].strip()


def test_info_lists_topics_types_counts_and_duration(write_bag, make):
    lines = describe(two_topic_bag(write_bag, make))
    # first message at 10.0 s (/chassis_cmd), last at 10.25 s (/chatter) -> 0.25 s
    assert value(lines, 'Duration') == '0.250000000s'
    assert value(lines, 'Messages') == '4'
    assert value(lines, 'Storage id') == 'mcap'
    text = '\n'.join(lines)
    assert (
        'Topic: /chassis_cmd | Type: rm_msgs/msg/ChassisCmd | Count: 3 | Serialization Format: cdr'
        in text
    )
    assert 'Topic: /chatter | Type: std_msgs/msg/String | Count: 1' in text
    assert '(10.000000000)' in value(lines, 'Start')
    assert '(10.250000000)' in value(lines, 'End')


def test_info_reads_sqlite3_bags(write_bag, make):
    lines = describe(two_topic_bag(write_bag, make, storage='sqlite3'))
    assert value(lines, 'Storage id') == 'sqlite3'
    assert value(lines, 'Files').endswith('.db3')
    assert value(lines, 'Messages') == '4'


def test_info_verb_prints_and_exits_0(write_bag, make, capsys):
    assert main(['bag', 'info', str(two_topic_bag(write_bag, make))]) == 0
    assert 'Count: 3' in capsys.readouterr().out


def test_sizes_use_binary_units():
    assert format_size(512) == '512 B'
    assert format_size(1536) == '1.5 KiB'  # 1536 / 1024
    assert format_size(3 * 1024**2) == '3.0 MiB'
