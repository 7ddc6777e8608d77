"""YAML <-> ROS messages with the semantics of ``ros2 topic pub`` and ``ros2 topic echo``.

Why one module: both directions of ros2 topic pub/echo's YAML rules, which share the type
introspection.

Reading (``topic pub``): ``fill_message(msg, parse_values(text))`` fills a message from
YAML like ``'{mode: GYRO, accel: {linear: {x: 1.0}}}'``. On top of ros2's syntax it
accepts the names of the message's integer constants for integer fields, case-insensitive
(``mode: gyro`` -> ``ChassisCmd.GYRO``; ``mode: [effort]`` -> ``ActuatorCmd.MODE_EFFORT``),
and, like Jazzy's ``ros2 topic pub``, ``header: auto`` and ``<time field>: now``, which
return setters that stamp the message with the current time at each publish.

Writing (``topic echo``): ``message_to_yaml`` / ``message_to_csv`` print what
rosidl_runtime_py prints (field order of the .msg file, truncation, ``--no-arr``/``--no-str``).

rosidl_runtime_py does the setting and printing when it imports (a real ROS install); the
PyPI wheels don't ship it, so this module carries small equivalents. Those had to be
written by hand; they check what generated messages no longer check themselves (Jazzy
only checks field types and ranges with ROS_PYTHON_CHECK_FIELDS=1): integer ranges,
float32 range, bounded strings and sequences, fixed array sizes. Every error names the
field path (``accel.linear.x``). No rclpy import here.
"""

from __future__ import annotations

import array
import difflib
import importlib
import math
import sys
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache, partial
from typing import Any

import numpy as np
import yaml
from rosidl_parser import definition as idl

from .errors import MessageFieldError
from .interfaces import type_name_of

TimestampSetter = Callable[[Any], None]
"""Called with a builtin_interfaces/msg/Time; sets one time field of a filled message."""

_HEADER = ('std_msgs', 'msg', 'Header')
_TIME = ('builtin_interfaces', 'msg', 'Time')
_INT_RANGES = {
    'int8': (-(2**7), 2**7 - 1),
    'uint8': (0, 2**8 - 1),
    'int16': (-(2**15), 2**15 - 1),
    'uint16': (0, 2**16 - 1),
    'int32': (-(2**31), 2**31 - 1),
    'uint32': (0, 2**32 - 1),
    'int64': (-(2**63), 2**63 - 1),
    'uint64': (0, 2**64 - 1),
}
_FLOAT32_MAX = 3.402823466e38
_FLOAT_TYPES = ('float', 'double', 'long double')


# ---------------------------------------------------------------------------------------------
# Type introspection


def field_slots(msg_class: Any) -> dict[str, idl.AbstractType]:
    """Return ``{field name: rosidl type}`` of a generated message class, in .msg order.

    (Any: rosidl makes the class and its introspection attributes at import.)
    """
    return dict(zip(msg_class.get_fields_and_field_types(), msg_class.SLOT_TYPES, strict=True))


def message_constants(msg_class: type) -> dict[str, Any]:
    """Return the constants of a generated message class (``{'GYRO': 4, ...}``)."""
    # The generated metaclass hands its constants to the class body through __prepare__;
    # field defaults are passed the same way, named <FIELD>__DEFAULT.
    constants = type(msg_class).__prepare__(msg_class.__name__, ())
    return {k: v for k, v in constants.items() if not k.endswith('__DEFAULT')}


def namespaced_class(slot: idl.NamespacedType) -> type:
    """Import the class of a nested message type."""
    module = importlib.import_module('.'.join(slot.namespaces))
    return getattr(module, slot.name)


def type_label(slot: idl.AbstractType) -> str:
    """Readable rosidl spelling of a field type (``double[3]``, ``string<=8``, ``pkg/msg/T``)."""
    if isinstance(slot, idl.Array):
        return f'{type_label(slot.value_type)}[{slot.size}]'
    if isinstance(slot, idl.BoundedSequence):
        return f'{type_label(slot.value_type)}[<={slot.maximum_size}]'
    if isinstance(slot, idl.UnboundedSequence):
        return f'{type_label(slot.value_type)}[]'
    if isinstance(slot, idl.BoundedString | idl.BoundedWString):
        return f'{"w" if isinstance(slot, idl.AbstractWString) else ""}string<={slot.maximum_size}'
    if isinstance(slot, idl.AbstractGenericString):
        return 'wstring' if isinstance(slot, idl.AbstractWString) else 'string'
    if isinstance(slot, idl.NamespacedType):
        return '/'.join(slot.namespaced_name())
    if isinstance(slot, idl.BasicType):
        return slot.typename
    return type(slot).__name__


def _one_line(err: object) -> str:
    return ' '.join(str(err).split())


def _unknown_field(msg_class: type, name: object, path: str) -> MessageFieldError:
    valid = ', '.join(field_slots(msg_class))
    return MessageFieldError(
        f"'{path}': {type_name_of(msg_class)} has no field '{name}'; valid fields: {valid}"
    )


def _join(prefix: str, name: object) -> str:
    return f'{prefix}.{name}' if prefix else str(name)


# ---------------------------------------------------------------------------------------------
# YAML -> message


def parse_values(text: str) -> dict:
    """Parse the values argument of ``topic pub`` (YAML flow or block mapping).

    An empty text is the empty mapping (all fields default).

    Raises:
        MessageFieldError: not YAML, or not a mapping.
    """
    try:
        values = yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise MessageFieldError(f'the values are not valid YAML: {_one_line(err)}') from None
    if values is None:
        return {}
    if not isinstance(values, dict):
        raise MessageFieldError(
            f"the values need to be a YAML mapping like '{{mode: GYRO}}', got {text!r}"
        )
    return values


def resolve_names(msg_class: type, values: Mapping, *, path: str = '') -> dict:
    """Check field names and replace constant names by their values, recursively.

    Args:
        msg_class: generated message class the values are for.
        values: field name -> value, as parsed from YAML.
        path: field path of ``values`` inside the top-level message (for errors).

    Returns:
        A copy of values with every integer given as a constant name replaced by the value
        of that constant of the message that holds the field.

    Raises:
        MessageFieldError: unknown field, or a name that is not a constant of the message.
    """
    if not isinstance(values, Mapping):
        raise MessageFieldError(
            f"'{path}' ({type_name_of(msg_class)}): expected a mapping of its fields, "
            f'got {values!r}'
        )
    slots = field_slots(msg_class)
    resolved = {}
    for name, value in values.items():
        field_path = _join(path, name)
        if name not in slots:
            raise _unknown_field(msg_class, name, field_path)
        resolved[name] = _resolve_value(msg_class, name, slots[name], value, field_path)
    return resolved


def _resolve_value(owner: type, field: str, slot: idl.AbstractType, value: Any, path: str):
    if isinstance(slot, idl.NamespacedType):
        if isinstance(value, Mapping):
            return resolve_names(namespaced_class(slot), value, path=path)
        return value  # 'auto', 'now', a message object, or a type error reported on setting
    if isinstance(slot, idl.AbstractNestedType):
        if isinstance(value, list | tuple):
            return [
                _resolve_value(owner, field, slot.value_type, item, f'{path}[{i}]')
                for i, item in enumerate(value)
            ]
        return value
    if isinstance(slot, idl.BasicType) and slot.typename in _INT_RANGES and isinstance(value, str):
        return _constant_value(owner, field, slot.typename, value, path)
    return value


def _constant_value(owner: type, field: str, typename: str, name: str, path: str) -> int:
    constants = {
        k: v
        for k, v in message_constants(owner).items()
        if isinstance(v, int) and not isinstance(v, bool)
    }
    key = name.strip().upper()
    # 'gyro' -> GYRO; for a field 'mode' also 'effort' -> MODE_EFFORT.
    for candidate in (key, f'{field.upper()}_{key}'):
        if candidate in constants:
            return constants[candidate]
    try:
        return int(name)  # a number in quotes, as ros2 topic pub's int() accepts
    except ValueError:
        pass
    if constants:
        valid = ', '.join(f'{k} ({v})' for k, v in constants.items())
        close = difflib.get_close_matches(key, list(constants), n=1)
        hint = f' (did you mean {close[0]}?)' if close else ''
        raise MessageFieldError(
            f"'{path}': unknown name '{name}' for {type_name_of(owner)}{hint}; "
            f'valid names: {valid}'
        )
    raise MessageFieldError(f"'{path}' ({typename}): expected an integer, got {name!r}")


def set_message_fields(
    msg: Any,
    values: Mapping,
    expand_header_auto: bool = False,
    expand_time_now: bool = False,
) -> list[TimestampSetter]:
    """Set the fields of a message from a mapping, like rosidl_runtime_py's function.

    Args:
        msg: message to fill in place.
        values: field name -> value; nested messages as mappings, arrays as lists.
        expand_header_auto: ``'auto'`` for a std_msgs/Header field leaves a default header
            and returns a setter for its ``stamp``.
        expand_time_now: ``'now'`` for a builtin_interfaces/Time field returns a setter for it.

    Returns:
        Setters to call with the current time before each publish (empty when neither
        keyword was used).

    Raises:
        MessageFieldError: unknown field, or a value that does not fit its field; the
            message names the field path.
    """
    fill = _Fill(header_auto=expand_header_auto, time_now=expand_time_now)
    _fill(msg, values, '', fill)
    return fill.setters


@dataclass
class _Fill:
    """What one set_message_fields call needs all the way down."""

    header_auto: bool
    time_now: bool
    setters: list[TimestampSetter] = field(default_factory=list)


def _fill(msg, values, path: str, fill: _Fill) -> None:
    cls = type(msg)
    if not isinstance(values, Mapping):
        raise MessageFieldError(
            f"'{path}' ({type_name_of(cls)}): expected a mapping of its fields, got {values!r}"
        )
    slots = field_slots(cls)
    for name, value in values.items():
        field_path = _join(path, name)
        slot = slots.get(name)
        if slot is None:
            raise _unknown_field(cls, name, field_path)
        if isinstance(slot, idl.NamespacedType):
            full_name = tuple(slot.namespaced_name())
            if fill.header_auto and full_name == _HEADER and value == 'auto':
                fill.setters.append(partial(setattr, getattr(msg, name), 'stamp'))
                continue
            if fill.time_now and full_name == _TIME and value == 'now':
                fill.setters.append(partial(setattr, msg, name))
                continue
        converted = _convert(slot, value, field_path, fill)
        try:
            setattr(msg, name, converted)
        except (AssertionError, TypeError, ValueError) as err:
            raise MessageFieldError(
                f"'{field_path}' ({type_label(slot)}): {_one_line(err)}"
            ) from None


def _convert(slot, value, path: str, fill: _Fill):
    def fail(expected: str) -> MessageFieldError:
        return MessageFieldError(
            f"'{path}' ({type_label(slot)}): expected {expected}, got {value!r}"
        )

    if isinstance(slot, idl.NamespacedType):
        cls = namespaced_class(slot)
        if isinstance(value, cls):
            return value
        if not isinstance(value, Mapping):
            raise fail('a mapping of its fields')
        sub = cls()
        _fill(sub, value, path, fill)
        return sub
    if isinstance(slot, idl.AbstractNestedType):
        if isinstance(value, str | bytes) or not isinstance(
            value, Sequence | array.array | np.ndarray
        ):
            raise fail('a list')
        if isinstance(slot, idl.Array) and len(value) != slot.size:
            raise fail(f'{slot.size} elements')
        if isinstance(slot, idl.BoundedSequence) and len(value) > slot.maximum_size:
            raise fail(f'at most {slot.maximum_size} elements')
        return [
            _convert(slot.value_type, item, f'{path}[{i}]', fill) for i, item in enumerate(value)
        ]
    if isinstance(slot, idl.AbstractGenericString):
        if isinstance(value, bool) or not isinstance(value, str | int | float):
            raise fail('a string')
        text = value if isinstance(value, str) else str(value)  # ros2: str(value)
        bounded = isinstance(slot, idl.BoundedString | idl.BoundedWString)
        if bounded and len(text) > slot.maximum_size:
            raise fail(f'at most {slot.maximum_size} characters')
        return text
    if isinstance(slot, idl.BasicType):
        return _convert_basic(slot.typename, value, fail)
    raise fail(f'a value of a supported type, not {type(slot).__name__}')


def _convert_basic(typename: str, value, fail):
    if typename == 'boolean':
        if isinstance(value, bool):
            return value
        raise fail('true or false')
    if typename in _FLOAT_TYPES:
        number = None
        if isinstance(value, int | float) and not isinstance(value, bool):
            number = float(value)
        elif isinstance(value, str):
            try:
                number = float(value)  # '1e-3', 'nan', 'inf', as ros2's float() accepts
            except ValueError:
                pass
        if number is None:
            raise fail('a number')
        if typename == 'float' and not math.isinf(number) and abs(number) > _FLOAT32_MAX:
            raise fail(f'a float32 within ±{_FLOAT32_MAX:g}')
        return number
    if typename in _INT_RANGES:
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int):
            raise fail('an integer')
        low, high = _INT_RANGES[typename]
        if not low <= value <= high:
            raise fail(f'an integer in [{low}, {high}]')
        return value
    if typename == 'octet':
        if isinstance(value, bytes) and len(value) == 1:
            return value
        if isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= 255:
            return bytes([value])
        raise fail('a byte (0..255)')
    if typename in ('char', 'wchar'):
        if isinstance(value, str) and len(value) == 1:
            return value
        if isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= 255:
            return value
        raise fail('a single character')
    raise fail(f'a value of a supported type, not {typename}')


@cache
def _rosidl_runtime_py():
    try:
        return importlib.import_module('rosidl_runtime_py')
    except ImportError:
        return None


def fill_message(msg: Any, values: Mapping) -> list[TimestampSetter]:
    """Fill msg from values as ``ros2 topic pub`` does, with constant names resolved.

    Field names and constant names are checked first (errors name the field path and the
    valid choices); then rosidl_runtime_py's ``set_message_fields`` sets the fields when it
    imports, else ``set_message_fields`` of this module. ``header: auto`` and ``now`` are on.

    Returns:
        Setters to call with the current time before each publish.

    Raises:
        MessageFieldError: the values do not fit the message.
    """
    resolved = resolve_names(type(msg), values)
    rosidl = _rosidl_runtime_py()
    if rosidl is None:
        return set_message_fields(msg, resolved, expand_header_auto=True, expand_time_now=True)
    try:
        return rosidl.set_message_fields(
            msg, resolved, expand_header_auto=True, expand_time_now=True
        )
    except Exception as err:
        raise MessageFieldError(f'failed to populate field: {_one_line(err)}') from None


# ---------------------------------------------------------------------------------------------
# message -> YAML / CSV


def _abbreviation(value, slot) -> str:
    element = slot.value_type
    if isinstance(element, idl.NamespacedType):
        element_name = '/'.join(element.namespaced_name())
    elif isinstance(element, idl.AbstractWString):
        element_name = 'wstring'
    elif isinstance(element, idl.AbstractString):
        element_name = 'string'
    else:
        element_name = getattr(element, 'typename', 'unknown')
    if isinstance(slot, idl.Array):
        return f'<array type: {element_name}[{slot.size}]>'
    if isinstance(slot, idl.BoundedSequence):
        return f'<sequence type: {element_name}[{slot.maximum_size}], length: {len(value)}>'
    return f'<sequence type: {element_name}, length: {len(value)}>'


def _plain(value, slot, truncate_length: int | None, no_arr: bool, no_str: bool):
    """One field value as plain Python data, as rosidl_runtime_py's _convert_value does."""
    def cut(length: int) -> bool:
        return truncate_length is not None and length > truncate_length

    if isinstance(value, bytes):
        text = ''.join(chr(c) for c in value[:truncate_length])
        return text + '...' if cut(len(value)) else text
    if isinstance(value, str):
        if no_str:
            return f'<string length: <{len(value)}>>'
        return value[:truncate_length] + '...' if cut(len(value)) else value
    if isinstance(value, list | tuple | array.array | np.ndarray):
        if no_arr and slot is not None:
            return _abbreviation(value, slot)
        items = [_plain(v, None, truncate_length, no_arr, no_str) for v in value[:truncate_length]]
        return [*items, '...'] if cut(len(value)) else items
    if isinstance(value, np.number | np.bool_):
        return value.item()
    if isinstance(value, bool | int | float):
        return value
    return message_to_ordereddict(
        value, truncate_length=truncate_length, no_arr=no_arr, no_str=no_str
    )


def message_to_ordereddict(
    msg: Any, *, truncate_length: int | None = None, no_arr: bool = False, no_str: bool = False
) -> OrderedDict:
    """Return the message as an OrderedDict of plain values, in .msg field order.

    Args:
        msg: a generated message.
        truncate_length: cut strings and arrays longer than this, appending ``'...'``.
        no_arr: replace array fields by a ``<sequence type: ...>`` summary.
        no_str: replace string fields by a ``<string length: <N>>`` summary.
    """
    return OrderedDict(
        (name, _plain(getattr(msg, name), slot, truncate_length, no_arr, no_str))
        for name, slot in field_slots(type(msg)).items()
    )


class _OrderedDumper(yaml.SafeDumper):
    """SafeDumper that writes OrderedDicts as plain mappings, keeping the field order."""


_OrderedDumper.add_representer(
    OrderedDict,
    lambda dumper, data: dumper.represent_mapping('tag:yaml.org,2002:map', data.items()),
)


def message_to_yaml(
    msg: Any,
    *,
    truncate_length: int | None = None,
    no_arr: bool = False,
    no_str: bool = False,
    flow_style: bool = False,
) -> str:
    """Return the message as YAML text, as ``ros2 topic echo`` prints it (without ``---``)."""
    rosidl = _rosidl_runtime_py()
    if rosidl is not None:
        return rosidl.message_to_yaml(
            msg,
            truncate_length=truncate_length,
            no_arr=no_arr,
            no_str=no_str,
            flow_style=flow_style,
        )
    return yaml.dump(
        message_to_ordereddict(msg, truncate_length=truncate_length, no_arr=no_arr, no_str=no_str),
        Dumper=_OrderedDumper,
        allow_unicode=True,
        width=sys.maxsize,
        default_flow_style=flow_style,
    )


def message_to_csv(
    msg: Any, *, truncate_length: int | None = None, no_arr: bool = False, no_str: bool = False
) -> str:
    """Return every leaf of the message, depth first, joined by commas (``echo --csv``)."""
    rosidl = _rosidl_runtime_py()
    if rosidl is not None:
        return rosidl.message_to_csv(
            msg, truncate_length=truncate_length, no_arr=no_arr, no_str=no_str
        )

    def flatten(value) -> list[str]:
        if isinstance(value, Mapping):
            return [leaf for v in value.values() for leaf in flatten(v)]
        if isinstance(value, list):
            return [leaf for v in value for leaf in flatten(v)]
        return [str(value)]

    plain = message_to_ordereddict(
        msg, truncate_length=truncate_length, no_arr=no_arr, no_str=no_str
    )
    return ','.join(flatten(plain))


# ---------------------------------------------------------------------------------------------
# Field selection (echo --field)


def check_field_path(msg_class: type, path: Sequence[str]) -> None:
    """Check that a dotted field path exists in a message type.

    Raises:
        MessageFieldError: a component is not a field (naming the valid ones), or the path
            goes into a field that is not a message.
    """
    cls: type | None = msg_class
    for depth, name in enumerate(path):
        where = '.'.join(path[: depth + 1])
        if cls is None:
            raise MessageFieldError(
                f"'{where}': '{'.'.join(path[:depth])}' is not a message, it has no fields"
            )
        slots = field_slots(cls)
        if name not in slots:
            raise _unknown_field(cls, name, where)
        slot = slots[name]
        cls = namespaced_class(slot) if isinstance(slot, idl.NamespacedType) else None


def get_field(msg: Any, path: Sequence[str]) -> Any:
    """Return the value at a field path (``['pose', 'pose', 'position']``)."""
    for name in path:
        msg = getattr(msg, name)
    return msg
