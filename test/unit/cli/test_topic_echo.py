"""topic echo's printing: YAML documents, --field, --csv, truncation (no ROS)."""

import io

import pytest
import yaml
from rm_bringup.cli.errors import CliError
from rm_bringup.cli.main import build_parser
from rm_bringup.cli.topic_echo import Printer

from rm_msgs.msg import ActuatorState, ChassisCmd


def printed(msg, *options):
    args = build_parser().parse_args(['topic', 'echo', '/x', *options])
    stream = io.StringIO()
    Printer(args, stream)(msg)
    return stream.getvalue()


def test_each_message_is_a_yaml_document_ended_by_dashes():
    out = printed(ChassisCmd(mode=4))
    assert out.endswith('\n---\n')
    assert yaml.safe_load(out.split('---\n')[0])['mode'] == 4


def test_field_selects_a_sub_message_or_a_value():
    msg = ChassisCmd(mode=3)
    msg.accel.linear.x = 0.5
    assert yaml.safe_load(printed(msg, '--field', 'accel.linear').split('---')[0]) == {
        'x': 0.5,
        'y': 0.0,
        'z': 0.0,
    }
    assert printed(msg, '--field', 'mode') == '3\n---\n'


def test_array_field_prints_as_a_list():
    assert printed(ActuatorState(position=[1.0, 2.5]), '--field', 'position') == '[1.0, 2.5]\n---\n'


def test_csv_is_one_line_per_message():
    assert printed(ChassisCmd(mode=2), '--csv') == (
        '0,0,,2,0.0,0.0,0.0,0.0,0.0,0.0,0.0,,0,0.0,0.0,0.0,0\n'
    )


def test_long_arrays_are_truncated_unless_full_length():
    msg = ActuatorState(name=[f'j{i}' for i in range(5)])
    assert yaml.safe_load(printed(msg, '-l', '2').split('---')[0])['name'] == ['j0', 'j1', '...']
    assert (
        len(yaml.safe_load(printed(msg, '-l', '2', '--full-length').split('---')[0])['name']) == 5
    )


def test_empty_field_is_an_error():
    with pytest.raises(CliError, match=r"invalid field value '\.\.'"):
        printed(ChassisCmd(), '--field', '..')
