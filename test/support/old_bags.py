"""Bags of a ChassisCmd recorded with another definition of it (older, or edited)."""

from rm_bringup.cli.bag_convert import message_with_defaults
from rm_bringup.cli.bag_types import msg_file
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

S = 1_000_000_000
CMD = 'rm_msgs/msg/ChassisCmd'


def older_store(edit):
    """Jazzy's types plus a ChassisCmd whose .msg text went through edit(text)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    text = edit(msg_file(CMD).read_text(encoding='utf-8'))
    store.register(get_types_from_msg(text, CMD))
    return store


def write_old_bag(path, store, **fields):
    """Three /chassis_cmd messages of store's ChassisCmd with fields, 10 ms apart."""
    msg = message_with_defaults(store, CMD, **fields)
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection('/chassis_cmd', CMD, typestore=store)
        for i in range(3):
            writer.write(connection, S + i * S // 100, store.serialize_cdr(msg, CMD))
    return path
