"""Build ROS messages whose every field holds a distinct, non-default value.

A message that survives a round trip field for field proves every field is carried; a
default-valued field would pass even if it were dropped, so every leaf gets a value
derived from its path and a seed.
"""

from __future__ import annotations

import importlib
import zlib

_INT_RANGES = {
    'int8': (-128, 127), 'uint8': (0, 255), 'byte': (0, 255), 'char': (0, 255),
    'int16': (-2**15, 2**15 - 1), 'uint16': (0, 2**16 - 1),
    'int32': (-2**31, 2**31 - 1), 'uint32': (0, 2**32 - 1),
    'int64': (-2**63, 2**63 - 1), 'uint64': (0, 2**64 - 1),
}


def message_class(type_name: str):
    """Return the class for 'pkg/msg/Name' or 'pkg/Name'."""
    parts = type_name.split('/')
    package, name = parts[0], parts[-1]
    return getattr(importlib.import_module(f'{package}.msg'), name)


def _leaf(type_name: str, key: str):
    """A value for a primitive field, non-default and distinct per key."""
    h = zlib.crc32(key.encode())
    if type_name == 'boolean':
        return True
    if type_name in ('float', 'double'):
        return float(h % 10000) / 8.0 + 0.125  # exact in float32 too
    if type_name in _INT_RANGES:
        lo, hi = _INT_RANGES[type_name]
        return lo + 1 + h % min(hi - lo - 1, 2**31)
    if type_name in ('string', 'wstring') or type_name.startswith('string<'):
        return f'v{h:x}'
    if type_name == 'octet':
        return bytes([1 + h % 255])
    raise TypeError(f'no sample for primitive type {type_name!r}')


def _value(type_name: str, key: str):
    if type_name.startswith('sequence<') or type_name.endswith(']'):
        if type_name.startswith('sequence<'):
            inner, count = type_name[len('sequence<'):-1].split(',', 1)[0], 3
        else:
            inner, size = type_name[:-1].split('[')
            count = int(size)
        return [_value(inner, f'{key}[{i}]') for i in range(count)]
    if '/' in type_name:
        return sample_message(message_class(type_name), key)
    return _leaf(type_name, key)


def sample_message(cls, seed: str = ''):
    """Return an instance of cls with every field set to a distinct non-default value."""
    msg = cls()
    for field, type_name in cls.get_fields_and_field_types().items():
        setattr(msg, field, _value(type_name, f'{seed}.{field}'))
    return msg
