"""The compiled control loop: built by set-up, used whole or not at all, sources as fall-back."""

import importlib
import json
import os
import subprocess
import sys

import pytest
from rm_base.runtime import compiled


def test_set_up_compiled_every_module_of_the_group():
    if os.environ.get(compiled.ENV) == '0':
        pytest.skip(f'{compiled.ENV}=0 asks for the sources')
    assert compiled.choose() is None, f'the loop runs from its sources: {compiled.choose()}'
    interpreted = [m for m in compiled.MODULES
                   if not compiled.running_compiled(importlib.import_module(m))]
    assert interpreted == []


def _stamp(tmp_path, **changes):
    built = {m: compiled.digest(compiled.source_path(m)) for m in compiled.MODULES}
    built.update(changes)
    path = tmp_path / compiled.STAMP_NAME
    path.write_text(json.dumps(built))
    return path


def test_a_source_changed_since_the_build_is_named(tmp_path):
    assert compiled.stale(stamp=_stamp(tmp_path)) == []
    changed = _stamp(tmp_path, **{'rm_base.hardware.bus': '0' * 64})
    assert compiled.stale(stamp=changed) == ['rm_base.hardware.bus']


def test_without_a_stamp_or_with_another_module_list_nothing_compiled_is_used(tmp_path):
    assert compiled.stale(stamp=tmp_path / 'missing.json') == list(compiled.MODULES)
    other = _stamp(tmp_path, **{'rm_base.no_such_module': '0' * 64})
    assert compiled.stale(stamp=other) == list(compiled.MODULES)
    (tmp_path / 'torn.json').write_text('{"rm_base.hardw')
    assert compiled.stale(stamp=tmp_path / 'torn.json') == list(compiled.MODULES)


def test_without_rm_plugins_installed_only_rm_base_modules_are_checked(tmp_path, monkeypatch):
    plugins = [m for m in compiled.MODULES if m.startswith('rm_plugins.')]
    assert plugins  # else this test checks nothing
    stamp = _stamp(tmp_path, **dict.fromkeys(plugins, '0' * 64))
    real = compiled._package_dir
    monkeypatch.setattr(compiled, '_package_dir', lambda p: None if p == 'rm_plugins' else real(p))
    assert compiled.stale(stamp=stamp) == []


def test_the_source_finder_finds_the_python_file_beside_the_extension_module():
    import rm_base.hardware

    finder = compiled._SourceFinder(compiled.MODULES)
    spec = finder.find_spec('rm_base.hardware.bus', rm_base.hardware.__path__)
    assert spec is not None and spec.origin.endswith('hardware/bus.py')
    assert finder.find_spec('rm_base.hardware.config', rm_base.hardware.__path__) is None


def test_the_environment_variable_runs_the_whole_group_from_source():
    code = ('import importlib, rm_base.runtime.compiled as c\n'
            'print(c.choose())\n'
            'print(sum(c.running_compiled(importlib.import_module(m)) for m in c.MODULES))\n')
    env = {**os.environ, compiled.ENV: '0'}
    out = subprocess.run([sys.executable, '-c', code], env=env, capture_output=True,
                         text=True, check=True).stdout.split()
    assert out == [f'{compiled.ENV}=0', '0']
