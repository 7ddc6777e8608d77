"""Compile the control loop's modules with mypyc, beside their sources (scripts/setup.sh).

Usage: python scripts/build_compiled.py [--if-changed | --clean]

The modules are those of ``rm_base.runtime.compiled.MODULES``, compiled as one group (one shared
library, ``rm_base/rm_base/native__mypyc.*.so``, and a small extension module next to each
source). The stamp that lets them be used is written last, so an interrupted build is never
imported. ``--if-changed`` builds only when the stamp does not match the sources and the
module list (what set-up runs); ``--clean`` removes what a build made. Why:
docs/ARCHITECTURE.md, "The compiled loop".
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_DIRS = {'rm_base': 'rm_base/rm_base', 'rm_plugins': 'rm_plugins/rm_plugins'}


def _built_files() -> list[Path]:
    return [p for d in PACKAGE_DIRS.values() for p in (ROOT / d).rglob('*.so')]


def main(argv: list[str]) -> int:
    if os.environ.get('PYTHONHASHSEED') != '0':
        # mypyc 1.13 walks some sets in hash order, and one of those orders fails on
        # DjiActuator.gear_ratio (docs/ARCHITECTURE.md): one order, the same every build.
        os.environ['PYTHONHASHSEED'] = '0'
        os.execv(sys.executable, [sys.executable, *argv])
    sys.path[:0] = [str(ROOT / 'rm_base'), str(ROOT / 'rm_plugins')]
    os.environ['RM_ROS2_COMPILED'] = '0'  # this process imports the sources
    from rm_base.runtime import compiled

    if argv[1:] == ['--if-changed'] and not compiled.stale():
        return 0
    compiled.stamp_path().unlink(missing_ok=True)
    for path in _built_files():
        path.unlink()
    if argv[1:] == ['--clean']:
        return 0

    from mypyc.build import mypycify
    from setuptools import setup

    os.chdir(ROOT)  # mypy.ini (mypy_path, strictness) is read from here
    found = {m: compiled.source_path(m) for m in compiled.MODULES}
    missing = [m for m, path in found.items() if path is None]
    if missing:
        raise SystemExit(f'[build_compiled] no source for {", ".join(missing)}')
    paths = [str(path.relative_to(ROOT)) for path in found.values() if path is not None]
    sources = {m: compiled.digest(path) for m, path in found.items() if path is not None}
    extensions = mypycify(
        [*paths, '--cache-dir', 'build/compiled/mypy_cache'],
        separate=[(paths, compiled.GROUP)], opt_level='3', debug_level='1',
        target_dir='build/compiled',
    )
    setup(
        name='rm_ros2_compiled', ext_modules=extensions, package_dir=PACKAGE_DIRS,
        packages=[], script_args=['--quiet', 'build_ext', '--inplace',
                                  '--build-temp', 'build/compiled/temp'],
    )
    compiled.stamp_path().write_text(json.dumps(sources, indent=1, sort_keys=True) + '\n')
    print(f'[build_compiled] {len(paths)} modules compiled')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
