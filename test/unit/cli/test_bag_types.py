"""Bag types: installed .msg files registered in rosbags, with rosidl's hashes."""

import json

import pytest
from ament_index_python.packages import get_package_share_directory
from rm_bringup.cli.bag_types import BagTypes, msg_file, rm_bag_types
from rm_bringup.cli.errors import BagError
from rosbags.typesys import Stores, get_typestore

RM_MSGS = [
    'ActuatorCmd',
    'ActuatorState',
    'CanFrame',
    'ChassisCmd',
    'ChassisState',
    'GimbalCmd',
    'GimbalState',
    'GpioCmd',
    'GpioState',
    'PluginState',
    'ShootCmd',
    'ShooterState',
]


def test_rm_bag_types_register_every_rm_msgs_message(bag_types):
    for name in RM_MSGS:
        assert bag_types.knows(f'rm_msgs/msg/{name}')


@pytest.mark.parametrize('name', RM_MSGS)
def test_rihs01_hash_matches_the_one_rosidl_generated(bag_types, name):
    # rosidl writes the type hash next to each message (share/rm_msgs/msg/<Name>.json); the
    # bag's type_description_hash must be the same, or tools reject the bag's definitions.
    generated = json.loads((msg_file(f'rm_msgs/msg/{name}').with_suffix('.json')).read_text())
    expected = next(
        h['hash_string']
        for h in generated['type_hashes']
        if h['type_name'] == f'rm_msgs/msg/{name}'
    )
    assert bag_types.typestore.hash_rihs01(f'rm_msgs/msg/{name}') == expected


def test_dependencies_are_read_from_their_own_packages():
    # From an empty store, ChassisState needs std_msgs/Header, builtin_interfaces/Time,
    # geometry_msgs/Twist and Vector3: all read from the installed .msg files.
    types = BagTypes(get_typestore(Stores.EMPTY))
    types.ensure('rm_msgs/msg/ChassisState')
    for used in (
        'std_msgs/msg/Header',
        'builtin_interfaces/msg/Time',
        'geometry_msgs/msg/Twist',
        'geometry_msgs/msg/Vector3',
    ):
        assert types.knows(used), used
    msgdef, _ = types.typestore.generate_msgdef('rm_msgs/msg/ChassisState', ros_version=2)
    assert 'MSG: geometry_msgs/Twist' in msgdef


def test_constants_come_with_the_types(bag_types):
    assert bag_types.constants('rm_msgs/msg/ChassisCmd')['GYRO'] == 4


def test_unknown_package_is_a_bag_error():
    with pytest.raises(BagError, match="package 'no_such_msgs' is not in the ament index"):
        BagTypes().ensure('no_such_msgs/msg/Thing')


def test_unknown_message_of_a_known_package_is_a_bag_error():
    with pytest.raises(BagError, match=r'Nope\.msg does not exist'):
        BagTypes().ensure('rm_msgs/msg/Nope')


def test_share_folder_is_found_through_the_ament_index():
    assert msg_file(
        'rm_msgs/msg/ChassisCmd'
    ).parent.parent.as_posix() == get_package_share_directory('rm_msgs')


def test_a_fresh_store_starts_from_jazzy():
    assert rm_bag_types().knows('nav_msgs/msg/Odometry')
