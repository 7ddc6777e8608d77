"""The maths layer (rm_base.control, rm_base.geometry) must import without ROS."""

import subprocess
import sys
from pathlib import Path

RM_BASE_SOURCE = Path(__file__).resolve().parents[2] / 'rm_base'

# Runs in a fresh interpreter so nothing the test session imported can hide a dependency.
CHECK = """
import importlib, pkgutil, sys
sys.path.insert(0, {source!r})
names = []
for package_name in ('rm_base.control', 'rm_base.geometry'):
    package = importlib.import_module(package_name)
    names.append(package_name)
    for module in pkgutil.walk_packages(package.__path__, package_name + '.'):
        importlib.import_module(module.name)
        names.append(module.name)
leaked = sorted(name for name in sys.modules if name == 'rclpy' or name.startswith('rclpy.'))
assert not leaked, f'importing the maths layer imported {{leaked}}'
print('\\n'.join(names))
"""


def test_when_maths_modules_imported_expect_no_rclpy():
    result = subprocess.run(
        # -I: isolated mode, no PYTHONPATH or user site that could pull in ROS paths.
        [sys.executable, '-I', '-c', CHECK.format(source=str(RM_BASE_SOURCE))],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    imported = result.stdout.split()
    # Guard against a vacuous pass: the walk found the modules this area defines.
    assert 'rm_base.control.pid' in imported
    assert 'rm_base.geometry.kinematics' in imported
