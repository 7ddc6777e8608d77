"""The type checker runs as a test: mypy with mypy.ini (strict below the ROS edge)."""

import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent


def test_mypy_finds_no_problems():
    # mypy's own cache in build/ (ignored by git): a second run checks only what changed
    result = subprocess.run(
        [sys.executable, '-m', 'mypy', '--cache-dir', str(ROOT / 'build' / 'mypy_cache')],
        cwd=ROOT, capture_output=True, text=True, check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr


def test_each_package_says_it_is_typed():
    # PEP 561: a checker reading an installed package uses its hints only with py.typed
    for package in ('rm_base', 'rm_plugins', 'rm_bringup'):
        assert (ROOT / package / package / 'py.typed').is_file(), package
        assert "'py.typed'" in (ROOT / package / 'setup.py').read_text(), package
