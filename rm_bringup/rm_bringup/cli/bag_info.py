"""``rmcli bag info``: files, size, duration and topics of a bag, like ``ros2 bag info``."""

from __future__ import annotations

import argparse
import datetime
from pathlib import Path

from .bag_io import STORAGE_SUFFIXES, open_bag, storage_files


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``bag info``."""
    parser.add_argument('bag_path', help='Bag to open (folder, .mcap or .db3)')


def format_size(size_bytes: int) -> str:
    """Size with a binary unit, as rosbag2 prints it (``12.3 KiB``)."""
    size = float(size_bytes)
    for unit in ('B', 'KiB', 'MiB', 'GiB'):
        if size < 1024 or unit == 'GiB':
            return f'{size:.0f} {unit}' if unit == 'B' else f'{size:.1f} {unit}'
        size /= 1024
    raise AssertionError('unreachable')


def format_time(stamp_ns: int) -> str:
    """``Nov 21 2026 06:15:00.123456789 (1763705700.123456789)`` in local time."""
    sec, nsec = divmod(stamp_ns, 10**9)
    when = datetime.datetime.fromtimestamp(sec)
    return f'{when:%b %d %Y %H:%M:%S}.{nsec:09d} ({sec}.{nsec:09d})'


def describe(path: Path) -> list[str]:
    """Return the lines of ``bag info`` for a bag.

    Raises:
        BagError: the bag cannot be read.
    """
    files = storage_files(path)
    with open_bag(path) as reader:
        lines = [
            f'Files:             {", ".join(f.name for f in files)}',
            f'Bag size:          {format_size(sum(f.stat().st_size for f in files))}',
            f'Storage id:        {STORAGE_SUFFIXES.get(files[0].suffix, "unknown")}',
            f'ROS Distro:        {reader.ros_distro or "unknown"}',
        ]
        count = reader.message_count
        if count:
            # rosbags' end_time is one past the last stamp; ros2 prints last - first.
            last_ns = reader.end_time - 1
            lines += [
                f'Duration:          {(last_ns - reader.start_time) * 1e-9:.9f}s',
                f'Start:             {format_time(reader.start_time)}',
                f'End:               {format_time(last_ns)}',
            ]
        else:
            lines += ['Duration:          0.000000000s', 'Start:', 'End:']
        lines.append(f'Messages:          {count}')
        topics = [
            f'Topic: {c.topic} | Type: {c.msgtype} | Count: {c.msgcount} | '
            f'Serialization Format: {c.ext.serialization_format}'
            for c in sorted(reader.connections, key=lambda c: c.topic)
        ]
    lines.append('Topic information: ' + ('\n' + ' ' * 19).join(topics))
    return lines


def run(args: argparse.Namespace) -> int:
    """Print the bag's summary."""
    print('\n'.join(describe(Path(args.bag_path))))
    return 0
