"""Opening and reading bags through rosbags, with every failure as one BagError line.

rosbags raises many kinds of errors for damaged files (ReaderError for a truncated MCAP,
OverflowError or struct errors for garbage inside one, sqlite3 errors...), during open
and while iterating. Only the rosbags calls are wrapped, so bugs elsewhere keep their
traceback.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import BagError

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.typesys.store import Typestore

STORAGE_SUFFIXES = {'.mcap': 'mcap', '.db3': 'sqlite3'}


def storage_files(path: Path) -> list[Path]:
    """The storage files of a bag folder (or the file itself)."""
    if path.is_dir():
        return sorted(p for p in path.iterdir() if p.suffix in STORAGE_SUFFIXES)
    return [path]


def _describe(path: Path) -> str:
    files = storage_files(path) if path.exists() else []
    return str(files[0]) if len(files) == 1 else str(path)


def _reason(err: BaseException, path: Path) -> str:
    text = ' '.join(str(err).split()) or type(err).__name__
    if 'end magic' in text:
        folder = path if path.is_dir() else path.parent
        text += f' (truncated: the recording did not stop cleanly): rmcli bag reindex {folder}'
    return text


@contextmanager
def open_bag(
    path: str | Path, *, typed: bool = False, default_typestore: Typestore | None = None
) -> Iterator[Any]:
    """Open a rosbag2 folder, .mcap or .db3 file; close it after.

    Args:
        path: the bag.
        typed: open with rosbags' AnyReader (messages can be deserialized with the types the
            bag embeds); else the plain rosbag2 Reader (raw CDR only).
        default_typestore: types for an AnyReader of a bag that embeds none.

    Raises:
        BagError: missing, unreadable, truncated or corrupted; the message names the file.
    """
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Reader

    path = Path(path)
    if not path.exists():
        raise BagError(f"bag '{path}' does not exist")
    if path.is_dir() and not (path / 'metadata.yaml').is_file():
        if storage_files(path):
            raise BagError(f"'{path}' has no metadata.yaml (its recording did not stop "
                           f'cleanly?): rmcli bag reindex {path}')
        raise BagError(f"'{path}' is not a bag: it has no metadata.yaml")
    try:
        reader = AnyReader([path], default_typestore=default_typestore) if typed else Reader(path)
        reader.open()
    except Exception as err:
        raise BagError(f'cannot read bag {_describe(path)}: {_reason(err, path)}') from None
    try:
        yield reader
    finally:
        with suppress(Exception):
            reader.close()


def read_messages(
    reader: Any,
    path: str | Path,
    connections: Collection[Connection] = (),
    start: int | None = None,
) -> Iterator[tuple[Connection, int, bytes]]:
    """Yield (connection, timestamp [ns], raw CDR) in time order from an open reader.

    Raises:
        BagError: the data is damaged part-way; the message names the file.
    """
    messages = iter(reader.messages(connections=connections, start=start))
    while True:
        try:
            item = next(messages)
        except StopIteration:
            return
        except Exception as err:
            where = Path(path)
            raise BagError(f'cannot read bag {_describe(where)}: {_reason(err, where)}') from None
        if not isinstance(item[1], int) or not isinstance(item[2], bytes | bytearray | memoryview):
            # a damaged sqlite3 row comes back with NULL columns, not as an error
            raise BagError(f'cannot read bag {_describe(Path(path))}: a message without '
                           f'{"timestamp" if not isinstance(item[1], int) else "data"}')
        yield item
