"""Every console script of every package is installed where `ros2 run` looks for it."""

import importlib.metadata
import os
import pathlib

import pytest
from ament_index_python.packages import get_package_prefix

PYTHON_PACKAGES = ['rm_base', 'rm_plugins', 'rm_bringup']


def _console_scripts(package):
    dist = importlib.metadata.distribution(package)
    return [ep for ep in dist.entry_points if ep.group == 'console_scripts']


SCRIPTS = [(pkg, ep) for pkg in PYTHON_PACKAGES for ep in _console_scripts(pkg)]


def test_the_packages_declare_console_scripts():
    assert {ep.name for _, ep in SCRIPTS} >= {'rm_robot', 'can_bridge'}


@pytest.mark.parametrize(('package', 'entry_point'), SCRIPTS, ids=[ep.name for _, ep in SCRIPTS])
def test_console_script_is_installed_in_lib_package(package, entry_point):
    # ros2 run <pkg> <exe> runs <prefix of pkg>/lib/<pkg>/<exe>.
    exe = pathlib.Path(get_package_prefix(package)) / 'lib' / package / entry_point.name
    assert exe.is_file(), f'{exe} missing: run scripts/setup.sh'
    assert os.access(exe, os.X_OK)
    interpreter = exe.read_text().splitlines()[0].removeprefix('#!').split()[0]
    assert os.access(interpreter, os.X_OK), f'{exe} names a missing interpreter {interpreter}'


@pytest.mark.parametrize(('package', 'entry_point'), SCRIPTS, ids=[ep.name for _, ep in SCRIPTS])
def test_console_script_target_imports(package, entry_point):
    assert callable(entry_point.load())


@pytest.mark.parametrize('name', ['can_bridge', 'rm_robot'])
def test_help_prints_the_usage_not_a_configuration_error(name):
    # The finding: `can_bridge --help` printed "configuration error: buses must be a mapping".
    import subprocess

    exe = pathlib.Path(get_package_prefix('rm_base')) / 'lib' / 'rm_base' / name
    done = subprocess.run([str(exe), '--help'], capture_output=True, text=True, timeout=60,
                          check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f'usage: {name} --ros-args --params-file ROBOT.yaml')
    assert 'configuration error' not in done.stdout + done.stderr
