"""``rmcli bag reindex``: make a bag whose recording was killed readable, like ``ros2 bag reindex``.

A recorder killed with SIGKILL (or a power cut) leaves the storage file without its end and
the folder without ``metadata.yaml``. For MCAP the records written before the kill are whole
and in order (the writer appends one chunk of about 1 MiB at a time; the chunk it was
filling is lost): :func:`repair_mcap_tail` cuts the file after its last whole record and
ends it with a Data End and a Footer without a summary, which every MCAP reader reads by
scanning. An SQLite file needs no repair (SQLite keeps a killed writer's database whole).
Then the storage is scanned (rosbags' storage readers) and ``metadata.yaml`` written in the
rosbag2 layout that rosbags' own writer uses (version 9).
"""

from __future__ import annotations

import argparse
import os
import struct
from pathlib import Path
from typing import Any

import yaml

from .bag_io import STORAGE_SUFFIXES, storage_files
from .errors import BagError

MCAP_MAGIC = b'\x89MCAP0\r\n'
_DATA_END = 0x0F
_FOOTER = 0x02
_RECORD_HEAD = struct.Struct('<BQ')  # opcode, length of the content
#: Data End (its data section CRC 0: not checked), then a Footer with no summary.
_MCAP_END = (
    _RECORD_HEAD.pack(_DATA_END, 4) + struct.pack('<I', 0)
    + _RECORD_HEAD.pack(_FOOTER, 20) + struct.pack('<QQI', 0, 0, 0) + MCAP_MAGIC
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``bag reindex``."""
    parser.add_argument('bag_path', help='bag folder whose recording did not stop cleanly')


def mcap_end_is_whole(data: bytes) -> bool:
    """Whether an MCAP file's bytes end with a footer and the closing magic."""
    return (len(data) >= 8 + 37 and data.endswith(MCAP_MAGIC)
            and data[-37:-28] == _RECORD_HEAD.pack(_FOOTER, 20))


def whole_records_end(data: bytes) -> tuple[int, bool]:
    """Where the last whole record of an MCAP file ends, and whether it is the Data End.

    Raises:
        BagError: the file does not start as an MCAP file does.
    """
    if not data:
        raise BagError('empty: the recording was killed before its first chunk (about '
                       '1 MiB) was written; there is nothing to recover')
    if not data.startswith(MCAP_MAGIC):
        raise BagError('not an MCAP file (no magic at its start)')
    pos = len(MCAP_MAGIC)
    while pos + _RECORD_HEAD.size <= len(data):
        opcode, length = _RECORD_HEAD.unpack_from(data, pos)
        end = pos + _RECORD_HEAD.size + length
        if end > len(data) or opcode == 0:  # cut short, or zeros the file system left
            break
        pos = end
        if opcode == _DATA_END:
            return pos, True
    return pos, False


def repair_mcap_tail(path: Path) -> int | None:
    """End an MCAP file whose writer was killed; return the bytes cut (None: it was whole).

    Raises:
        BagError: not an MCAP file, or not even its header is whole.
    """
    data = path.read_bytes()
    if mcap_end_is_whole(data):
        return None
    try:
        end, at_data_end = whole_records_end(data)
    except BagError as err:
        raise BagError(f'{path}: {err}') from None
    if end <= len(MCAP_MAGIC):
        raise BagError(f'{path}: not even the MCAP header is whole')
    with path.open('r+b') as out:
        out.truncate(end)
        out.seek(end)
        out.write(_MCAP_END[_RECORD_HEAD.size + 4:] if at_data_end else _MCAP_END)
        out.flush()
        os.fsync(out.fileno())
    return len(data) - end


def _scan(path: Path) -> Any:
    """An open rosbags storage reader of one file (its connections carry their counts)."""
    # rosbags has no public API to read a storage file without metadata.yaml
    from rosbags.rosbag2.storage_mcap import McapReader
    from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

    reader = McapReader(path) if path.suffix == '.mcap' else Sqlite3Reader(path)
    reader.open()
    return reader


def metadata(files: list[Path], readers: list[Any]) -> dict[str, Any]:
    """``metadata.yaml`` of a bag of these storage files, as rosbags' writer writes it."""
    from rosbags.rosbag2.metadata import dump_qos_v9

    topics: dict[tuple[str, str], dict[str, Any]] = {}
    entries = []
    start, end, total = 2**63 - 1, 0, 0
    for path, reader in zip(files, readers, strict=True):
        meta = reader.metadata
        count = sum(c.msgcount for c in reader.connections)
        first = meta.start_time if count else 0
        last = meta.end_time - 1 if count else 0
        for c in reader.connections:
            key = (c.topic, c.msgtype)
            entry = topics.setdefault(key, {
                'topic_metadata': {
                    'name': c.topic, 'type': c.msgtype,
                    'serialization_format': c.ext.serialization_format,
                    'offered_qos_profiles': dump_qos_v9(c.ext.offered_qos_profiles),
                    'type_description_hash': c.digest,
                },
                'message_count': 0,
            })
            entry['message_count'] += c.msgcount
        if count:
            start, end = min(start, first), max(end, last)
        total += count
        entries.append({
            'path': path.name,
            'starting_time': {'nanoseconds_since_epoch': first},
            'duration': {'nanoseconds': max(0, last - first)},
            'message_count': count,
        })
    if not total:
        start = end = 0
    return {'rosbag2_bagfile_information': {
        'version': 9,
        'storage_identifier': STORAGE_SUFFIXES[files[0].suffix],
        'relative_file_paths': [f.name for f in files],
        'duration': {'nanoseconds': max(0, end - start)},
        'starting_time': {'nanoseconds_since_epoch': start},
        'message_count': total,
        'topics_with_message_count': list(topics.values()),
        'compression_format': '',
        'compression_mode': '',
        'files': entries,
        'custom_data': {'reindexed_by': 'rmcli bag reindex'},
        'ros_distro': 'rosbags',
    }}


def reindex(path: Path) -> list[str]:
    """Repair the storage files of a bag folder and write its metadata.yaml; say what.

    Raises:
        BagError: no such folder, no storage file, or one that cannot be read.
    """
    if not path.is_dir():
        raise BagError(f"'{path}' is not a bag folder")
    files = storage_files(path)
    if not files:
        raise BagError(f"'{path}' holds no .mcap or .db3 file")
    if len({f.suffix for f in files}) != 1:
        raise BagError(f"'{path}' mixes storage kinds: {', '.join(f.name for f in files)}")
    said, readers = [], []
    try:
        for f in files:
            if f.suffix == '.mcap':
                cut = repair_mcap_tail(f)
                if cut is not None:
                    said.append(f'{f.name}: closed after its last whole record'
                                + (f' ({cut} bytes of an unfinished one cut)' if cut else ''))
            try:
                readers.append(_scan(f))
            except Exception as err:  # rosbags raises many kinds for a damaged file
                raise BagError(f'cannot read {f}: {" ".join(str(err).split())}') from None
        meta = metadata(files, readers)
    finally:
        for reader in readers:
            reader.close()
    target = path / 'metadata.yaml'
    tmp = target.with_suffix('.yaml.tmp')
    tmp.write_text(yaml.safe_dump(meta, sort_keys=False), encoding='utf-8')
    tmp.replace(target)
    info = meta['rosbag2_bagfile_information']
    said.append(f"wrote {target}: {info['message_count']} messages on "
                f"{len(info['topics_with_message_count'])} topics")
    return said


def run(args: argparse.Namespace) -> int:
    """Reindex the bag; print what was done."""
    for line in reindex(Path(args.bag_path)):
        print(line)
    return 0
