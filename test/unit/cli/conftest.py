"""Fixtures for the rmcli unit tests: small bags written with rosbags."""

import pytest
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
        cls = store.types[msgtype]
        values = {}
        for name, desc in store.fielddefs[msgtype][1]:
            if name in fields:
                values[name] = fields[name]
            else:
                values[name] = _default(store, desc)
        return cls(**values)

    return build


def _default(store, desc):
    import numpy as np
    from rosbags.interfaces import Nodetype

    kind, detail = desc
    if kind == Nodetype.NAME:
        cls = store.types[detail]
        return cls(**{n: _default(store, d) for n, d in store.fielddefs[detail][1]})
    if kind == Nodetype.BASE:
        typename = detail[0]
        if typename == 'string':
            return ''
        if typename == 'bool':
            return False
        return 0.0 if typename.startswith('float') else 0
    if kind == Nodetype.ARRAY:
        inner, size = detail
        if inner[0] == Nodetype.BASE and inner[1][0] != 'string':
            return np.zeros(size, dtype=np.float64 if inner[1][0].startswith('float') else np.int64)
        return [_default(store, inner) for _ in range(size)]
    # sequences: empty
    inner = detail[0]
    if inner[0] == Nodetype.BASE and inner[1][0] not in ('string', 'bool'):
        dtype = np.float64 if inner[1][0].startswith('float') else np.uint8
        return np.array([], dtype=dtype)
    return []
