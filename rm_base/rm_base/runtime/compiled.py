"""The control loop's modules that run compiled, and the fall-back to their sources.

Why: on a 2-vCPU machine the loop's own Python work is what misses the 1 kHz deadlines
(docs/PERFORMANCE.md, "The busiest modules are compiled"). These modules are typed
throughout, so mypyc (the compiler that ships with mypy) turns them into C extension
modules, which set-up builds beside their sources (``scripts/build_compiled.py``). The
sources stay the reference and the only thing edited.

The group is used all or none: compiled modules call each other directly, so one of them
from its source beside the others compiled would not be the code that was built. The
sources run instead (slower, same behaviour) when

* ``RM_ROS2_COMPILED=0`` is set (profiling Python lines, debugging), or
* the group was not built, or a source changed since it was (``make setup`` rebuilds).

:func:`choose` decides once per process, before the first of these modules is imported
(``rm_base/__init__.py`` calls it), and says why the sources run. No rclpy here.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.abc
import importlib.machinery
import importlib.util
import json
import logging
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType

#: The compiled modules: the loop's hardware side and the plugins' busiest helpers.
MODULES: tuple[str, ...] = (
    'rm_base.loop.timing',
    'rm_base.loop.scheduler',
    'rm_base.hardware.bus',
    'rm_base.hardware.actuators.base',
    'rm_base.motors.dji.actuator',
    'rm_base.motors.dji.groups',
    'rm_base.sim.wire',
    'rm_base.geometry.angles',
    'rm_base.host.plugin_task',
    'rm_plugins.chassis.motion',
    'rm_plugins.chassis.odometry',
    'rm_plugins.gimbal.control',
)
#: The group's shared library is ``rm_base/<GROUP tail>__mypyc.*.so``.
GROUP = 'rm_base.native'
#: Environment variable: ``0`` runs the sources even when the compiled modules are built.
ENV = 'RM_ROS2_COMPILED'
#: What the build compiled: ``{module: sha256 of its source}``, written last by the build.
STAMP_NAME = 'compiled_stamp.json'

_log = logging.getLogger(__name__)


# rm_base's own folder (this module lives in rm_base/runtime/)
_RM_BASE = Path(__file__).parents[1]


def _package_dir(package: str) -> Path | None:
    if package == 'rm_base':
        return _RM_BASE
    spec = importlib.util.find_spec(package)  # finds, does not import
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(spec.submodule_search_locations[0])


def source_path(module: str) -> Path | None:
    """The source file of one of the project's modules (``rm_base.hardware.bus``).

    None when its package is not installed (rm_base alone, without rm_plugins).
    """
    package, *rest = module.split('.')
    directory = _package_dir(package)
    return None if directory is None else directory.joinpath(*rest[:-1], rest[-1] + '.py')


def stamp_path() -> Path:
    """Where the build records what it compiled."""
    return _RM_BASE / STAMP_NAME


def digest(path: Path) -> str:
    """sha256 of a file's bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def stale(modules: Sequence[str] = MODULES, stamp: Path | None = None) -> list[str]:
    """The modules whose source is not the one compiled (all of them without a build)."""
    try:
        built = json.loads((stamp or stamp_path()).read_text())
    except (OSError, ValueError):
        return list(modules)
    if set(built) != set(modules):
        return list(modules)
    # a module of a package not installed is never imported: it cannot be stale
    sources = {m: source_path(m) for m in modules}
    return [m for m, path in sources.items() if path is not None and built[m] != digest(path)]


class _SourceFinder(importlib.abc.MetaPathFinder):
    """Finds the group's modules as their ``.py`` files, before the extension modules."""

    def __init__(self, modules: Sequence[str]) -> None:
        self._modules = frozenset(modules)

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None,
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in self._modules or not path:
            return None
        # path: the parent package's __path__, so the source beside the extension module
        source = Path(path[0], fullname.rpartition('.')[2] + '.py')
        return importlib.util.spec_from_file_location(fullname, source)


@functools.cache
def choose() -> str | None:
    """Use the compiled group if it is built and current, else its sources; once per process.

    Returns:
        Why the sources run (None: the compiled modules do); the same on every call.
    """
    if os.environ.get(ENV, '1') == '0':
        reason = f'{ENV}=0'
    elif not stamp_path().exists():
        reason = 'not built (make setup builds it)'
    else:
        changed = stale()
        if not changed:
            return None
        reason = f'{", ".join(changed)} changed since the build (make setup rebuilds it)'
        _log.warning('rm_ros2: the loop runs from its sources, slower: %s', reason)
    sys.meta_path.insert(0, _SourceFinder(MODULES))
    return reason


def running_compiled(module: ModuleType) -> bool:
    """Whether an imported module is a compiled extension module."""
    return not str(getattr(module, '__file__', '')).endswith('.py')
