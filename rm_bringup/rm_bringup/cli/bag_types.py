"""Message types for bags: rosbags' Jazzy typestore plus the .msg files of installed packages.

The Jazzy typestore knows std/geometry/sensor/nav/diagnostic/rcl_interfaces messages. Any
other type (rm_msgs, a test package) is read from ``share/<pkg>/msg/<Name>.msg`` through
the ament index and registered with ``get_types_from_msg``, together with every type it
uses that the store does not know yet. The definitions and RIHS01 hashes rosbags then
writes into a bag are those rosidl computes (test_bag_types checks this against rclpy).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from .errors import BagError
from .interfaces import normalize_type_name

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore


def _referenced_types(field_desc) -> Iterator[str]:
    """Yield the message type names a rosbags field description refers to."""
    from rosbags.interfaces import Nodetype

    kind, detail = field_desc
    if kind == Nodetype.NAME:
        yield detail
    elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        yield from _referenced_types(detail[0])


def msg_file(msgtype: str) -> Path:
    """Return the installed .msg file of ``pkg/msg/Name``.

    Raises:
        BagError: the package is not in the ament index or has no such .msg file.
    """
    from ament_index_python.packages import PackageNotFoundError, get_package_share_directory

    package, _, name = normalize_type_name(msgtype).split('/')
    try:
        share = Path(get_package_share_directory(package))
    except (PackageNotFoundError, ValueError):
        raise BagError(
            f"no definition for '{msgtype}': package '{package}' is not in the ament index "
            '(is the workspace sourced?)'
        ) from None
    path = share / 'msg' / f'{name}.msg'
    if not path.is_file():
        raise BagError(f"no definition for '{msgtype}': {path} does not exist")
    return path


class BagTypes:
    """A rosbags typestore that learns installed message types on demand."""

    def __init__(self, typestore: Typestore | None = None) -> None:
        """Start from typestore, or from rosbags' ROS 2 Jazzy store."""
        from rosbags.typesys import Stores, get_typestore

        self.typestore = typestore if typestore is not None else get_typestore(Stores.ROS2_JAZZY)

    def knows(self, msgtype: str) -> bool:
        """Whether msgtype is registered already."""
        return msgtype in self.typestore.fielddefs

    def ensure(self, msgtype: str) -> None:
        """Register msgtype and the types it uses, reading installed .msg files as needed.

        Raises:
            BagError: a definition is missing or does not parse.
        """
        from rosbags.typesys import TypesysError

        msgtype = normalize_type_name(msgtype)
        pending: dict = {}
        self._collect(msgtype, pending)
        if pending:
            try:
                self.typestore.register(pending)
            except TypesysError as err:
                raise BagError(f"cannot register '{msgtype}': {err}") from None

    def _collect(self, msgtype: str, pending: dict) -> None:
        from rosbags.typesys import TypesysError, get_types_from_msg

        if self.knows(msgtype) or msgtype in pending:
            return
        path = msg_file(msgtype)
        try:
            types = get_types_from_msg(path.read_text(encoding='utf-8'), msgtype)
        except TypesysError as err:
            raise BagError(f'cannot parse {path}: {err}') from None
        pending.update(types)
        for _, field_desc in types[msgtype][1]:
            for used in _referenced_types(field_desc):
                self._collect(used, pending)

    def ensure_package(self, package: str) -> list[str]:
        """Register every message of an installed package; return their type names."""
        from ament_index_python.packages import PackageNotFoundError, get_package_share_directory

        try:
            msg_dir = Path(get_package_share_directory(package)) / 'msg'
        except (PackageNotFoundError, ValueError):
            raise BagError(f"package '{package}' is not in the ament index") from None
        names = sorted(f'{package}/msg/{path.stem}' for path in msg_dir.glob('*.msg'))
        for name in names:
            self.ensure(name)
        return names

    def constants(self, msgtype: str) -> dict[str, int | float | str | bool]:
        """Return ``{name: value}`` of the constants of a registered type (empty if unknown)."""
        if not self.knows(msgtype):
            return {}
        return {name: value for name, _, value in self.typestore.fielddefs[msgtype][0]}


def rm_bag_types() -> BagTypes:
    """A BagTypes with every rm_msgs message registered."""
    types = BagTypes()
    types.ensure_package('rm_msgs')
    return types
