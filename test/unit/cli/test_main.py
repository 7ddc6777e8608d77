"""rmcli's command line: verbs, option parsing and exit codes (no ROS started here)."""

import pytest
from rm_bringup.cli.main import build_parser, main
from rm_bringup.cli.topic_pub import split_type_and_values


def test_no_arguments_list_the_command_groups(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert 'topic' in out and 'bag' in out


@pytest.mark.parametrize(
    ('group', 'verbs'),
    [('topic', ['echo', 'hz', 'list', 'pub']), ('bag', ['info', 'play', 'plot', 'record'])],
)
def test_a_group_alone_lists_its_verbs(capsys, group, verbs):
    assert main([group]) == 0
    out = capsys.readouterr().out
    for verb in verbs:
        assert verb in out


def test_help_exits_0(capsys):
    with pytest.raises(SystemExit) as info:
        main(['topic', 'pub', '--help'])
    assert info.value.code == 0
    assert '--wait-matching-subscriptions' in capsys.readouterr().out


@pytest.mark.parametrize(
    'argv',
    [
        ['topic', 'nope'],
        ['topic', 'pub'],  # no topic
        ['topic', 'pub', '--once', '--times', '3', '/x'],  # mutually exclusive, like ros2
        ['topic', 'pub', '-r', '0', '/x'],  # rate must be positive
        ['topic', 'pub', '-t', '-2', '/x'],
        ['topic', 'echo', '/x', '--truncate-length', '-1'],
        ['topic', 'hz', '/x', '--window', '0'],
        ['bag', 'record', '-s', 'rosbag1', '-a'],
        ['bag', 'play', 'x', '--rate', '-1'],
        ['bag', 'plot', 'x'],  # -o is required
    ],
)
def test_usage_errors_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert 'error' in capsys.readouterr().err


def test_pub_options_parse_like_ros2():
    args = build_parser().parse_args(
        [
            'topic',
            'pub',
            '-1',
            '-w',
            '2',
            '-r',
            '5',
            '-p',
            '0',
            '/chassis_cmd',
            'rm_msgs/msg/ChassisCmd',
            '{mode: GYRO}',
        ]
    )
    assert (args.once, args.wait_matching_subscriptions, args.rate, args.print) == (True, 2, 5.0, 0)
    assert (args.topic_name, args.message_type, args.values) == (
        '/chassis_cmd',
        'rm_msgs/msg/ChassisCmd',
        '{mode: GYRO}',
    )
    assert args.qos_profile == 'default'  # ros2 topic pub's default preset


def test_echo_defaults_to_sensor_data_qos_and_128_truncation():
    args = build_parser().parse_args(['topic', 'echo', '/odom'])
    assert (args.qos_profile, args.truncate_length, args.once) == ('sensor_data', 128, False)


@pytest.mark.parametrize(
    ('first', 'second', 'expected'),
    [
        (None, None, (None, '{}')),
        ('rm_msgs/msg/ChassisCmd', None, ('rm_msgs/msg/ChassisCmd', '{}')),
        ('std_msgs/String', None, ('std_msgs/String', '{}')),
        ('{mode: GYRO}', None, (None, '{mode: GYRO}')),
        ('mode: 4', None, (None, 'mode: 4')),
        ('rm_msgs/msg/ChassisCmd', '{mode: 4}', ('rm_msgs/msg/ChassisCmd', '{mode: 4}')),
    ],
)
def test_a_single_positional_after_the_topic_is_a_type_only_if_it_looks_like_one(
    first, second, expected
):
    assert split_type_and_values(first, second) == expected


def one_error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert 'Traceback' not in '\n'.join(err)
    return err[-1]


def test_max_wait_without_anything_to_wait_for_is_a_usage_error(capsys):
    assert (
        main(['topic', 'pub', '-w', '0', '--max-wait-time-secs', '1', '/x', 'std_msgs/msg/String'])
        == 2
    )
    assert '--max-wait-time-secs' in one_error_line(capsys)


def test_bad_values_fail_before_any_ros_node_with_exit_1(capsys):
    assert main(['topic', 'pub', '--once', '/x', 'rm_msgs/msg/ChassisCmd', '{mode: SPIN}']) == 1
    line = one_error_line(capsys)
    assert line.startswith('rmcli: error:') and 'SPIN' in line and 'GYRO (4)' in line


def test_unknown_type_is_one_line_exit_1(capsys):
    assert main(['topic', 'pub', '/x', 'rm_msgs/msg/ChasisCmd', '{}']) == 1
    assert 'rm_msgs has no message ChasisCmd' in one_error_line(capsys)


def test_unknown_echo_field_fails_before_subscribing(capsys):
    assert main(['topic', 'echo', '/x', 'rm_msgs/msg/ChassisCmd', '--field', 'accel.speed']) == 1
    assert "'accel.speed'" in one_error_line(capsys)


def test_record_needs_something_to_record(capsys, tmp_path):
    assert main(['bag', 'record', '-o', str(tmp_path / 'b')]) == 2
    assert 'need to specify' in one_error_line(capsys)


def test_record_refuses_an_existing_output_folder(capsys, tmp_path):
    assert main(['bag', 'record', '-a', '-o', str(tmp_path)]) == 1
    assert 'already exists' in one_error_line(capsys)
