"""Fixtures for the rmcli unit tests: small bags written with rosbags."""

import pytest
from rm_bringup.cli.bag_convert import message_with_defaults
from rm_bringup.cli.bag_types import rm_bag_types
from rosbags.rosbag2 import StoragePlugin, Writer


@pytest.fixture(scope='session')
def bag_types():
    """rosbags' Jazzy typestore with every rm_msgs message registered."""
    return rm_bag_types()


@pytest.fixture
def write_bag(tmp_path, bag_types):
    """write_bag(samples, name='bag', storage='mcap') -> path of a new bag.

    samples: (topic, msgtype, timestamp [ns], rosbags message) in any order.
    """
    store = bag_types.typestore

    def write(samples, name='bag', storage='mcap'):
        path = tmp_path / name
        with Writer(path, version=9, storage_plugin=StoragePlugin[storage.upper()]) as writer:
            connections = {}
            for topic, msgtype, stamp, msg in sorted(samples, key=lambda s: s[2]):
                if topic not in connections:
                    connections[topic] = writer.add_connection(topic, msgtype, typestore=store)
                writer.write(connections[topic], stamp, store.serialize_cdr(msg, msgtype))
        return path

    return write


@pytest.fixture
def make(bag_types):
    """make('pkg/msg/Type', **fields) -> rosbags message with defaults for the other fields."""
    store = bag_types.typestore

    def build(msgtype, **fields):
        return message_with_defaults(store, msgtype, **fields)

    return build
