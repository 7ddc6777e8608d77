"""bench/'s modules for the tests that check them (bench/ is a package at the repository
root, which is not on the test path)."""

import importlib
import pathlib
import sys
from types import ModuleType

ROOT = pathlib.Path(__file__).resolve().parents[2]


def bench_module(name: str) -> ModuleType:
    """``bench.<name>``, imported with the repository root on the path for the import only."""
    sys.path.insert(0, str(ROOT))
    try:
        return importlib.import_module(f'bench.{name}')
    finally:
        sys.path.remove(str(ROOT))
