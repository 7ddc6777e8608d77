"""Bags recorded with an older definition of a type are played as the installed type."""

import threading

import pytest
from rclpy.serialization import deserialize_message
from rm_bringup.cli.bag_convert import conversions
from rm_bringup.cli.bag_io import open_bag
from rm_bringup.cli.bag_play import PlayOptions, play
from rm_bringup.cli.errors import BagError
from support.old_bags import CMD, S, older_store, write_old_bag

from rm_msgs.msg import ChassisCmd


def drop_follow_source_add_legacy_gain(text):
    assert 'string follow_source' in text
    return text.replace('string follow_source', 'float64 legacy_gain')


def test_a_field_added_since_recording_gets_its_default_and_a_dropped_one_is_named(tmp_path):
    store = older_store(drop_follow_source_add_legacy_gain)
    accel = store.types['geometry_msgs/msg/Accel'](
        linear=store.types['geometry_msgs/msg/Vector3'](x=2.5, y=0.0, z=0.0),
        angular=store.types['geometry_msgs/msg/Vector3'](x=0.0, y=0.0, z=4.0),
    )
    bag = write_old_bag(tmp_path / 'old', store, mode=ChassisCmd.GYRO, accel=accel,
                        power_limit=55.0, legacy_gain=3.0)
    with open_bag(bag) as reader:
        found = conversions(reader.connections)
        (conversion,) = found.values()
        assert conversion.added == ('follow_source',)
        assert conversion.dropped == ('legacy_gain',)
        assert 'follow_source' in conversion.describe('/chassis_cmd')
        assert 'not played: legacy_gain' in conversion.describe('/chassis_cmd')
        sent = []
        publisher = type('P', (), {'publish': lambda self, raw: sent.append(raw)})()
        count = play(reader, bag, reader.connections, {'/chassis_cmd': publisher},
                     options=PlayOptions(rate=100.0), stop=threading.Event(), converted=found)
    assert count == len(sent) == 3
    msg = deserialize_message(sent[0], ChassisCmd)
    assert (msg.mode, msg.power_limit, msg.follow_source) == (ChassisCmd.GYRO, 55.0, '')
    assert (msg.accel.linear.x, msg.accel.angular.z) == (2.5, 4.0)


def test_a_bag_of_the_installed_definition_is_played_as_recorded(write_bag, make):
    bag = write_bag([('/chassis_cmd', CMD, S, make(CMD, mode=ChassisCmd.RAW))])
    with open_bag(bag) as reader:
        assert conversions(reader.connections) == {}


@pytest.mark.parametrize(
    ('edit', 'message'),
    [
        (lambda t: t.replace('uint8 mode', 'string mode'),
         'field mode was string when recorded, is uint8 now'),
        (lambda t: t.replace('geometry_msgs/Accel accel', 'geometry_msgs/Twist accel'),
         'field accel was geometry_msgs/msg/Twist when recorded, is geometry_msgs/msg/Accel now'),
    ],
    ids=['kind', 'nested-type'],
)
def test_a_field_that_changed_its_type_refuses_the_topic_naming_it(tmp_path, edit, message):
    bag = write_old_bag(tmp_path / 'old', older_store(edit))
    with open_bag(bag) as reader, pytest.raises(BagError, match=f'/chassis_cmd: {message}'):
        conversions(reader.connections)
