"""The house drawn from the imports: layers import downward only (.importlinter).

`lint-imports` (import-linter) builds the graph of every import of rm_base, rm_plugins
and rm_bringup, direct or through other modules, and checks the contracts of .importlinter:
the layers, top to bottom, and the pure layers that must run without ROS.
"""

import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
LINT = pathlib.Path(sys.executable).with_name('lint-imports')


def lint(config: pathlib.Path) -> subprocess.CompletedProcess:
    env = {'PYTHONPATH': ':'.join(str(ROOT / p) for p in ('rm_base', 'rm_plugins', 'rm_bringup')),
           'PATH': '/usr/bin:/bin'}
    return subprocess.run([str(LINT), '--config', str(config), '--no-cache'], cwd=ROOT, env=env,
                          capture_output=True, text=True, check=False)


def test_every_layer_imports_only_the_layers_below_it():
    result = lint(ROOT / '.importlinter')
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr
    assert 'Contracts: 2 kept, 0 broken.' in result.stdout


def test_an_import_up_a_layer_is_caught(tmp_path):
    # Not vacuous: the graph has the edges. The motors are built on the hardware layer, so
    # a contract that has the hardware above the motors must break, naming the import.
    config = (ROOT / '.importlinter').read_text().replace(
        '    rm_base.motors\n    rm_base.sim_devices\n    rm_base.hardware\n',
        '    rm_base.hardware\n    rm_base.sim_devices\n    rm_base.motors\n')
    assert config != (ROOT / '.importlinter').read_text()
    (tmp_path / 'upside_down').write_text(config)
    result = lint(tmp_path / 'upside_down')
    assert result.returncode != 0
    assert 'rm_base.motors' in result.stdout and 'rm_base.hardware' in result.stdout
    assert 'BROKEN' in result.stdout
