"""YAML <-> message: ros2 topic pub/echo semantics plus constant names and field paths."""

import math
import types

import pytest
import yaml
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseWithCovariance
from nav_msgs.msg import Path
from rm_bringup.cli import message_yaml
from rm_bringup.cli.errors import MessageFieldError
from rm_bringup.cli.message_yaml import (
    check_field_path,
    fill_message,
    message_to_csv,
    message_to_yaml,
    parse_values,
    set_message_fields,
)
from rmw_dds_common.msg import NodeEntitiesInfo
from sensor_msgs.msg import JoyFeedback
from shape_msgs.msg import SolidPrimitive
from std_msgs.msg import Float32, Header, String
from support.msg_samples import message_class, sample_message

from rm_msgs.msg import ActuatorCmd, ChassisCmd, GimbalCmd, ShooterState


def filled(cls, text):
    msg = cls()
    fill_message(msg, parse_values(text))
    return msg


# --- parse_values ----------------------------------------------------------------------------


def test_flow_and_block_yaml_parse_to_the_same_mapping():
    assert parse_values('{mode: 4, accel: {linear: {x: 1.5}}}') == parse_values(
        'mode: 4\naccel:\n  linear:\n    x: 1.5\n'
    )


def test_empty_values_mean_all_defaults():
    assert parse_values('') == {}


def test_when_values_are_not_a_mapping_expect_error():
    with pytest.raises(MessageFieldError, match='YAML mapping'):
        parse_values('[1, 2]')


def test_when_values_are_not_yaml_expect_one_line_error():
    with pytest.raises(MessageFieldError, match='not valid YAML') as info:
        parse_values('{mode: [1, }')
    assert '\n' not in str(info.value)


# --- filling: nested, arrays, constants ------------------------------------------------------


def test_nested_fields_are_set_and_others_keep_defaults():
    msg = filled(
        ChassisCmd, '{accel: {linear: {x: 1.5}, angular: {z: -2}}, follow_source: base_link}'
    )
    assert msg.accel.linear.x == 1.5
    assert msg.accel.angular.z == -2.0  # an int for a float64 field becomes a float
    assert isinstance(msg.accel.angular.z, float)
    assert msg.accel.linear.y == 0.0
    assert msg.follow_source == 'base_link'
    assert msg.mode == 0


@pytest.mark.parametrize(
    ('text', 'mode'),
    [('GYRO', ChassisCmd.GYRO), ('gyro', 4), ('Twist', 3), ('4', 4), (2, 2)],
)
def test_mode_accepts_constant_names_case_insensitive_and_numbers(text, mode):
    assert filled(ChassisCmd, yaml.safe_dump({'mode': text})).mode == mode


def test_array_of_modes_accepts_field_prefixed_constant_names():
    # ActuatorCmd's constants are MODE_OFF.. MODE_MIT; for field 'mode', 'effort' = MODE_EFFORT.
    msg = filled(
        ActuatorCmd, '{name: [yaw, pitch], mode: [effort, MODE_MIT, 2], position: [1, 2.5]}'
    )
    assert list(msg.mode) == [ActuatorCmd.MODE_EFFORT, ActuatorCmd.MODE_MIT, 2]
    assert list(msg.position) == [1.0, 2.5]
    assert msg.name == ['yaw', 'pitch']


def test_constant_names_resolve_in_nested_messages_of_other_packages():
    # JoyFeedback.type takes TYPE_LED/TYPE_RUMBLE/TYPE_BUZZER: 'rumble' -> TYPE_RUMBLE = 1.
    msg = filled(JoyFeedback, '{type: rumble, intensity: 0.5}')
    assert msg.type == JoyFeedback.TYPE_RUMBLE


def test_when_mode_name_is_unknown_expect_error_listing_valid_names():
    with pytest.raises(MessageFieldError) as info:
        filled(ChassisCmd, '{mode: SPIN}')
    text = str(info.value)
    assert "'mode'" in text and "'SPIN'" in text
    for name, value in [('PASSIVE', 0), ('RAW', 1), ('FOLLOW', 2), ('TWIST', 3), ('GYRO', 4)]:
        assert f'{name} ({value})' in text
    assert 'did you mean' not in text  # nothing near SPIN


def test_a_misspelled_mode_name_gets_the_nearest_one():
    with pytest.raises(MessageFieldError) as info:
        filled(ChassisCmd, '{mode: gyroo}')
    assert "unknown name 'gyroo' for rm_msgs/msg/ChassisCmd (did you mean GYRO?); " \
        'valid names: PASSIVE (0)' in str(info.value)


def test_when_a_name_is_given_for_an_int_field_without_constants_expect_type_error():
    with pytest.raises(MessageFieldError, match=r"'stamp.sec' \(int32\): expected an integer"):
        filled(Header, '{stamp: {sec: soon}}')


def test_fixed_size_array_takes_exactly_its_size():
    covariance = list(range(36))
    msg = filled(PoseWithCovariance, yaml.safe_dump({'covariance': covariance}))
    assert list(msg.covariance) == [float(v) for v in covariance]
    with pytest.raises(
        MessageFieldError, match=r"'covariance' \(double\[36\]\): expected 36 elements"
    ):
        filled(PoseWithCovariance, '{covariance: [1, 2, 3]}')


def test_bounded_sequence_takes_at_most_its_bound():
    assert list(filled(SolidPrimitive, '{type: box, dimensions: [1, 2, 3]}').dimensions) == [
        1,
        2,
        3,
    ]
    with pytest.raises(
        MessageFieldError, match=r"'dimensions' \(double\[<=3\]\): expected at most 3"
    ):
        filled(SolidPrimitive, '{dimensions: [1, 2, 3, 4]}')


def test_bounded_string_takes_at_most_its_bound():
    ok = 'n' * 256
    assert filled(NodeEntitiesInfo, yaml.safe_dump({'node_name': ok})).node_name == ok
    with pytest.raises(
        MessageFieldError, match=r"'node_name' \(string<=256\): expected at most 256"
    ):
        filled(NodeEntitiesInfo, yaml.safe_dump({'node_name': ok + 'x'}))


def test_sequence_of_messages_from_a_list_of_mappings():
    msg = filled(Path, '{poses: [{pose: {position: {x: 1}}}, {header: {frame_id: odom}}]}')
    assert len(msg.poses) == 2
    assert msg.poses[0].pose.position.x == 1.0
    assert msg.poses[1].header.frame_id == 'odom'


# --- errors name the field path --------------------------------------------------------------


def test_when_field_is_unknown_expect_its_path_and_the_valid_fields():
    with pytest.raises(MessageFieldError) as info:
        filled(ChassisCmd, '{accel: {lineer: {x: 1}}}')
    assert "'accel.lineer'" in str(info.value)
    assert 'geometry_msgs/msg/Accel' in str(info.value)
    assert 'valid fields: linear, angular' in str(info.value)


def test_when_a_number_is_not_a_number_expect_path_and_type():
    with pytest.raises(
        MessageFieldError, match=r"'accel.linear.x' \(double\): expected a number, got 'fast'"
    ):
        filled(ChassisCmd, '{accel: {linear: {x: fast}}}')


def test_when_an_element_of_a_sequence_is_wrong_expect_its_index_in_the_path():
    with pytest.raises(MessageFieldError, match=r"'poses\[1\].pose.position.y' \(double\)"):
        filled(Path, '{poses: [{}, {pose: {position: {y: [1]}}}]}')


@pytest.mark.parametrize(
    ('text', 'pattern'),
    [
        ('{mode: 256}', r"'mode' \(uint8\): expected an integer in \[0, 255\], got 256"),
        ('{mode: -1}', r'in \[0, 255\]'),
        ('{mode: 1.5}', r'expected an integer, got 1.5'),
        ('{mode: true}', 'expected an integer'),
        ('{accel: 3}', r"'accel' \(geometry_msgs/msg/Accel\): expected a mapping"),
        ('{follow_source: [a]}', r"'follow_source' \(string\): expected a string"),
        ('{power_limit: null}', 'expected a number'),
    ],
)
def test_wrong_types_and_ranges_are_rejected_with_the_field(text, pattern):
    with pytest.raises(MessageFieldError, match=pattern):
        filled(ChassisCmd, text)


def test_float32_range_is_checked():
    # 3.5e38 > float32 max (~3.4028e38); inf is a valid float32.
    with pytest.raises(MessageFieldError, match=r"'data' \(float\)"):
        filled(Float32, '{data: 3.5e38}')
    assert math.isinf(filled(Float32, '{data: .inf}').data)


def test_bool_field_rejects_strings():
    # ros2's bool('false') would be True; a clear error is safer on a robot.
    from std_msgs.msg import Bool

    with pytest.raises(MessageFieldError, match='expected true or false'):
        filled(Bool, "{data: 'false'}")
    assert filled(Bool, '{data: false}').data is False


def test_numbers_for_string_fields_become_strings_like_ros2():
    assert filled(String, '{data: 42}').data == '42'


# --- header: auto, stamp: now ----------------------------------------------------------------


def test_header_auto_returns_a_setter_for_the_stamp():
    msg = ChassisCmd()
    setters = fill_message(msg, parse_values('{header: auto, mode: GYRO}'))
    assert len(setters) == 1
    assert msg.header.stamp == Time()  # untouched until the setter runs
    for set_stamp in setters:
        set_stamp(Time(sec=12, nanosec=34))
    assert msg.header.stamp == Time(sec=12, nanosec=34)
    assert msg.header.frame_id == ''


def test_stamp_now_and_nested_now_return_setters():
    msg = GimbalCmd()
    setters = fill_message(
        msg, parse_values('{header: {stamp: now, frame_id: odom}, target: {header: {stamp: now}}}')
    )
    assert len(setters) == 2
    for set_stamp in setters:
        set_stamp(Time(sec=7))
    assert msg.header.stamp.sec == 7
    assert msg.target.header.stamp.sec == 7
    assert msg.header.frame_id == 'odom'


def test_auto_for_a_non_header_field_is_an_error():
    with pytest.raises(MessageFieldError, match="'accel'"):
        filled(ChassisCmd, '{accel: auto}')


def test_own_set_message_fields_without_expansion_treats_auto_as_a_value():
    with pytest.raises(MessageFieldError, match="'header'"):
        set_message_fields(ChassisCmd(), {'header': 'auto'})


# --- rosidl_runtime_py when it imports -------------------------------------------------------


def test_when_rosidl_runtime_py_imports_expect_it_to_set_the_resolved_values(monkeypatch):
    calls = []

    def fake_set(msg, values, expand_header_auto=False, expand_time_now=False):
        calls.append((values, expand_header_auto, expand_time_now))
        return []

    fake = types.SimpleNamespace(set_message_fields=fake_set)
    monkeypatch.setattr(message_yaml, '_rosidl_runtime_py', lambda: fake)
    fill_message(ChassisCmd(), {'mode': 'gyro'})
    # Names are resolved (and fields checked) before rosidl_runtime_py sees the values.
    assert calls == [({'mode': 4}, True, True)]


def test_rosidl_runtime_py_errors_become_one_line_field_errors(monkeypatch):
    def fake_set(msg, values, **kwargs):
        raise AttributeError("'ChassisCmd' object has\nno attribute")

    monkeypatch.setattr(
        message_yaml,
        '_rosidl_runtime_py',
        lambda: types.SimpleNamespace(set_message_fields=fake_set),
    )
    with pytest.raises(MessageFieldError, match=r'failed to populate field: .* has no attribute'):
        fill_message(ChassisCmd(), {})


# --- message -> YAML / CSV -------------------------------------------------------------------


def test_yaml_is_in_field_order_like_ros2_topic_echo():
    msg = ChassisCmd(mode=4, follow_source='gimbal')
    msg.accel.linear.x = 1.5
    assert message_to_yaml(msg) == (
        'header:\n'
        '  stamp:\n'
        '    sec: 0\n'
        '    nanosec: 0\n'
        "  frame_id: ''\n"
        'mode: 4\n'
        'accel:\n'
        '  linear:\n'
        '    x: 1.5\n'
        '    y: 0.0\n'
        '    z: 0.0\n'
        '  angular:\n'
        '    x: 0.0\n'
        '    y: 0.0\n'
        '    z: 0.0\n'
        'power_limit: 0.0\n'
        'follow_source: gimbal\n'
        'speed_gear: 0\n'
        'move_x: 0.0\n'
        'move_y: 0.0\n'
        'move_yaw: 0.0\n'
        'move_id: 0\n'
    )


def test_arrays_print_as_lists_and_truncate_with_dots():
    msg = ActuatorCmd(name=['a', 'b', 'c'], position=[1.0, 2.0, 3.0])
    out = yaml.safe_load(message_to_yaml(msg, truncate_length=2))
    assert out['name'] == ['a', 'b', '...']
    assert out['position'] == [1.0, 2.0, '...']


def test_no_arr_and_no_str_summarise_fields():
    msg = ShooterState(reason='jam', friction_speed=[1.0, 2.0])
    out = yaml.safe_load(message_to_yaml(msg, no_arr=True, no_str=True))
    assert out['friction_speed'] == '<sequence type: double, length: 2>'
    assert out['reason'] == '<string length: <3>>'


def test_csv_lists_every_leaf_in_order():
    msg = ChassisCmd(mode=3, power_limit=80.0, follow_source='x')
    # header.stamp.sec, nanosec, frame_id, mode, accel (6 floats), power_limit, follow_source,
    # speed_gear
    assert message_to_csv(msg) == '0,0,,3,0.0,0.0,0.0,0.0,0.0,0.0,80.0,x,0,0.0,0.0,0.0,0'


RM_MSGS = [
    'ChassisCmd',
    'GimbalCmd',
    'ShootCmd',
    'ActuatorCmd',
    'ActuatorState',
    'PluginState',
    'ChassisState',
    'GimbalState',
    'ShooterState',
    'GpioCmd',
    'GpioState',
    'CanFrame',
]


@pytest.mark.parametrize('name', RM_MSGS)
def test_echo_output_fed_back_to_pub_gives_the_same_message(name):
    # Every field holds a distinct non-default value, so a dropped field would show.
    cls = message_class(f'rm_msgs/msg/{name}')
    original = sample_message(cls, name)
    copy = cls()
    fill_message(copy, parse_values(message_to_yaml(original)))
    assert copy == original


# --- --field ---------------------------------------------------------------------------------


def test_field_path_is_checked_against_the_type():
    check_field_path(ChassisCmd, ['accel', 'linear', 'x'])
    with pytest.raises(MessageFieldError, match=r"'accel\.lin'.*valid fields: linear, angular"):
        check_field_path(ChassisCmd, ['accel', 'lin'])
    with pytest.raises(MessageFieldError, match="'mode' is not a message"):
        check_field_path(ChassisCmd, ['mode', 'x'])
