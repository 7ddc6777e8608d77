"""Messages recorded with an older definition of their type, rebuilt in the installed one.

A bag carries each topic's message definition. When the installed type differs (a field
added to ChassisCmd since the bag was recorded), the recorded CDR no longer decodes as the
installed type. :func:`conversion_for` compares the two definitions and gives a
:class:`Conversion` that decodes a message with the recorded definition and rebuilds it in
the installed one: fields of the same name and kind are copied, fields added since take
their default (0, false, '', empty), and fields the installed type no longer has are named
in :attr:`Conversion.dropped` so the caller can say so. A field whose kind changed (uint8
to string, a nested type renamed, a fixed array resized) has no faithful copy: the topic
is refused with the field named. rosbags does the decoding and encoding; this module only
maps one definition's fields onto the other's.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

from .bag_io import read_messages
from .bag_types import BagTypes
from .errors import BagError

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.typesys.store import Typestore

_MISSING = object()

# numpy dtypes of the ROS primitive types (rosbags holds numeric arrays as numpy arrays)
_NUMPY = {
    'bool': 'bool', 'byte': 'uint8', 'char': 'uint8', 'octet': 'uint8',
    'int8': 'int8', 'uint8': 'uint8', 'int16': 'int16', 'uint16': 'uint16',
    'int32': 'int32', 'uint32': 'uint32', 'int64': 'int64', 'uint64': 'uint64',
    'float32': 'float32', 'float64': 'float64',
}


@dataclass(frozen=True)
class Conversion:
    """Rebuilds one topic's recorded messages in the installed definition of its type.

    Attributes:
        msgtype: the message type, e.g. ``rm_msgs/msg/ChassisCmd``.
        added: dotted names of installed fields the recording lacks (given defaults).
        dropped: dotted names of recorded fields the installed type lacks (not played).
        recorded: the types as the bag defines them (decodes the recorded CDR).
        installed: the installed types (encodes the rebuilt message).
    """

    msgtype: str
    added: tuple[str, ...]
    dropped: tuple[str, ...]
    recorded: Typestore
    installed: Typestore

    def __call__(self, raw: bytes | bytearray | memoryview) -> bytes:
        """The message of raw (recorded CDR) as installed CDR."""
        old = self.recorded.deserialize_cdr(bytes(raw), self.msgtype)
        new = _build(self.installed, self.msgtype, old)
        return bytes(self.installed.serialize_cdr(new, self.msgtype))

    def describe(self, topic: str) -> str:
        """One line for the user: what the conversion does to topic's messages."""
        text = f'{topic} was recorded with another definition of {self.msgtype}: converting'
        if self.added:
            text += f'; new fields at their defaults: {", ".join(self.added)}'
        if self.dropped:
            lacking = ', '.join(self.dropped)
            text += f'; recorded fields the installed type lacks, not played: {lacking}'
        return text


def conversion_for(connection: Connection, types: BagTypes) -> Conversion | None:
    """How to play connection's messages as the installed type; None when they match.

    A connection without a recorded definition is taken to match (nothing to compare).

    Raises:
        BagError: the recorded definition does not parse, or a field changed its kind.
    """
    from rosbags.typesys import Stores, TypesysError, get_types_from_msg, get_typestore

    msgtype = connection.msgtype
    definition = getattr(connection.msgdef, 'data', '') or ''
    if not definition.strip():
        return None
    types.ensure(msgtype)
    installed = types.typestore
    recorded = get_typestore(Stores.EMPTY)
    try:
        recorded.register(get_types_from_msg(definition, msgtype))
        same = recorded.hash_rihs01(msgtype) == installed.hash_rihs01(msgtype)
    except TypesysError as err:
        raise BagError(f'{connection.topic}: the recorded definition of {msgtype} '
                       f'does not parse: {err}') from None
    if same:
        return None
    walk = _Comparison(recorded, installed, connection.topic)
    walk.message(msgtype, msgtype)
    return Conversion(msgtype, tuple(walk.added), tuple(walk.dropped), recorded, installed)


class _Comparison:
    """Walks the recorded and the installed definition of a type side by side."""

    def __init__(self, recorded: Typestore, installed: Typestore, topic: str) -> None:
        self.recorded, self.installed, self.topic = recorded, installed, topic
        self.added: list[str] = []
        self.dropped: list[str] = []

    def message(self, old_type: str, new_type: str, prefix: str = '') -> None:
        old_fields = dict(self.recorded.fielddefs[old_type][1])
        new_fields = dict(self.installed.fielddefs[new_type][1])
        for name, desc in new_fields.items():
            if name in old_fields:
                self.field(old_fields[name], desc, prefix + name)
            else:
                self.added.append(prefix + name)
        self.dropped.extend(prefix + name for name in old_fields if name not in new_fields)

    def field(self, old: Any, new: Any, path: str) -> None:
        from rosbags.interfaces import Nodetype

        (old_kind, old_detail), (new_kind, new_detail) = old, new
        was = f'was {old_detail[0] if new_kind == Nodetype.BASE else old_detail} when recorded'
        if old_kind != new_kind:
            raise self._refused(path, 'changed its kind since the bag was recorded')
        if new_kind == Nodetype.BASE:
            if old_detail != new_detail:
                raise self._refused(path, f'{was}, is {new_detail[0]} now')
        elif new_kind == Nodetype.NAME:
            if old_detail != new_detail:
                raise self._refused(path, f'{was}, is {new_detail} now')
            self.message(old_detail, new_detail, path + '.')
        else:  # ARRAY or SEQUENCE: (element, length or bound)
            if old_detail[1] != new_detail[1]:
                raise self._refused(path, 'changed its length or bound since the bag was recorded')
            self.field(old_detail[0], new_detail[0], path + '[]')

    def _refused(self, path: str, change: str) -> BagError:
        return BagError(f'{self.topic}: field {path} {change}; '
                        'its messages cannot be played as the installed type')


def message_with_defaults(store: Typestore, msgtype: str, **fields: Any) -> Any:
    """A rosbags msgtype message with fields as given and every other field at its default."""
    return _build(store, msgtype, SimpleNamespace(**fields))


def _build(store: Typestore, msgtype: str, old: Any) -> Any:
    """An installed msgtype message with old's fields where it has them (old may be None)."""
    values = {}
    for name, desc in store.fielddefs[msgtype][1]:
        previous = _MISSING if old is None else getattr(old, name, _MISSING)
        values[name] = _value(store, desc, previous)
    return store.types[msgtype](**values)


def _value(store: Typestore, desc: Any, old: Any) -> Any:
    import numpy as np
    from rosbags.interfaces import Nodetype

    kind, detail = desc
    if kind == Nodetype.BASE:
        if old is not _MISSING:
            return old
        name = detail[0]
        if name in ('string', 'wstring'):
            return ''
        if name == 'bool':
            return False
        return 0.0 if name.startswith('float') else 0
    if kind == Nodetype.NAME:
        return _build(store, detail, None if old is _MISSING else old)
    element, length = detail
    element_kind, element_detail = element
    if element_kind == Nodetype.BASE and element_detail[0] in _NUMPY:
        if old is not _MISSING:
            return old
        return np.zeros(length if kind == Nodetype.ARRAY else 0, dtype=_NUMPY[element_detail[0]])
    if old is not _MISSING:
        return [_value(store, element, item) for item in old]
    count = length if kind == Nodetype.ARRAY else 0
    return [_value(store, element, _MISSING) for _ in range(count)]


def conversions(connections: Any, types: BagTypes | None = None) -> dict[int, Conversion]:
    """The conversions the connections need, by connection id (those that match: none).

    Raises:
        BagError: a topic cannot be played as its installed type (see :func:`conversion_for`).
    """
    types = types if types is not None else BagTypes()
    found = {}
    for connection in connections:
        conversion = conversion_for(connection, types)
        if conversion is not None:
            found[connection.id] = conversion
    return found


def read_installed(
    reader: Any, path: Any, connections: Any = (), start: int | None = None,
) -> Iterator[tuple[Connection, int, bytes | bytearray | memoryview]]:
    """As :func:`.bag_io.read_messages`, each message in the installed definition of its type.

    Raises:
        BagError: damaged data, or a topic that cannot be played as its installed type.
    """
    converted = conversions(connections or reader.connections)
    for connection, stamp, raw in read_messages(reader, path, connections, start):
        conversion = converted.get(connection.id)
        yield connection, stamp, raw if conversion is None else conversion(raw)
