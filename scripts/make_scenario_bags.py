#!/usr/bin/env python3
"""Write the replay scenario bags (test/data/<scenario>/) from test/replay/scenarios.py.

    source scripts/env.sh
    python scripts/make_scenario_bags.py                 # every scenario, into test/data
    python scripts/make_scenario_bags.py square --out /tmp/bags

Each bag is a rosbag2 folder (metadata.yaml + one MCAP file, zstd-compressed chunks as
ros2 bag's MCAP storage writes them) with the scenario's command streams: every message
at its bag time, header stamps equal to the time since the bag start. Types and their
definitions come from rosbags' Jazzy store and the installed rm_msgs (rmcli's bag types),
so `rmcli bag info/play` and `ros2 bag` read the bags. Rerunning rewrites the bags; the
same scenario gives the same messages (test/replay/test_scenario_bags.py checks that the
committed bags match their scenarios). Starts no ROS node.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / 'test' / 'data'
QOS_DEPTH = 10  # the offered QoS recorded for each topic: reliable, volatile, keep last 10


def scenarios() -> dict:
    """The scenarios of test/replay/scenarios.py by name."""
    if str(ROOT / 'test') not in sys.path:
        sys.path.insert(0, str(ROOT / 'test'))
    from replay.scenarios import SCENARIOS

    return SCENARIOS


def write_bag(scenario, path: Path) -> Path:
    """Write scenario's commands into a new bag folder at path (which must not exist)."""
    from rclpy.qos import QoSProfile
    from rclpy.serialization import serialize_message
    from rm_bringup.cli.bag_types import BagTypes
    from rm_bringup.cli.qos import to_bag_qos
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

    types = BagTypes()
    store = types.typestore
    offered = [to_bag_qos(QoSProfile(depth=QOS_DEPTH))]
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with writer:
        connections = {}
        for topic, msgtype in scenario.topics:
            types.ensure(msgtype)
            connections[topic] = writer.add_connection(
                topic, msgtype, typestore=store, offered_qos_profiles=offered
            )
        for t_ns, topic, msgtype, msg in scenario.messages():
            # rclpy leaves CDR padding uninitialised; a round trip through rosbags zeroes
            # it, so the same scenario always gives the same bytes (no churn in git).
            cdr = store.serialize_cdr(
                store.deserialize_cdr(serialize_message(msg), msgtype), msgtype
            )
            writer.write(connections[topic], t_ns, cdr)
    return path


def make(names: list[str], out: Path) -> list[Path]:
    """Write the named scenarios' bags into out/<name>/, replacing old ones."""
    known = scenarios()
    unknown = [n for n in names if n not in known]
    if unknown:
        raise SystemExit(f'unknown scenario(s): {", ".join(unknown)}; known: {", ".join(known)}')
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name in names or list(known):
        with tempfile.TemporaryDirectory(dir=out) as tmp:
            fresh = write_bag(known[name], Path(tmp) / name)
            target = out / name
            if target.exists():
                shutil.rmtree(target)
            fresh.rename(target)
        written.append(target)
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('names', nargs='*', help='scenarios to write (default: all)')
    parser.add_argument('--out', type=Path, default=DATA, help=f'folder (default: {DATA})')
    args = parser.parse_args(argv)
    for path in make(args.names, args.out):
        size = sum(f.stat().st_size for f in path.iterdir())
        print(f'{path}: {size / 1024:.1f} KiB')
    return 0


if __name__ == '__main__':
    sys.exit(main())
