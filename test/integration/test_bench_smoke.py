"""The benchmark runner does not rot: ``bench/run.py --quick`` prints every table row.

Numbers are not checked here (benchmarks are not tests, and this shared 2-core machine
could not hold any timing bound): only that each measurement ran and that the table and
the JSON result carry every declared row. The runner's ROS processes use this test
session's private ROS domain.
"""

import json
import os
import pathlib
import sys

import pytest
from support.bench import bench_module
from support.ros import start_process

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

ROOT = pathlib.Path(__file__).resolve().parents[2]
TIMEOUT = 180.0  # [s] the quick run takes ~15 s on a quiet machine; generous under load


def _rows():
    module = bench_module('report')
    return module.ROWS, module.SECTIONS


def _run_bench(out, *args):
    """Run bench/run.py with args in this session's ROS domain; return its stdout."""
    command = [sys.executable, str(ROOT / 'bench' / 'run.py'), *args, '--out', str(out)]
    command += ['--domain-id', os.environ['ROS_DOMAIN_ID']]
    proc = start_process(command, cwd=ROOT)
    stdout, stderr = proc.communicate(timeout=TIMEOUT)
    assert proc.returncode == 0, stdout[-3000:] + stderr[-3000:]
    return stdout


def test_when_run_quick_expect_every_row_in_the_table_and_the_json(tmp_path):
    rows, sections = _rows()
    stdout = _run_bench(tmp_path, '--quick')
    for title in sections.values():
        assert title in stdout
    table_lines = [line for line in stdout.splitlines() if line.startswith('| ')]
    for row in rows:
        assert any(line.startswith(f'| {row.label} ') for line in table_lines), row.label
    results = list(tmp_path.glob('bench-*.json'))
    assert len(results) == 1
    data = json.loads(results[0].read_text())
    assert [r['key'] for r in data['rows']] == [row.key for row in rows]
    # every measurement produced its raw result (not only a printed 'n/a')
    assert all(
        len(data['raw'][name]) == 1
        for name in ('robot', 'throughput', 'baseline', 'split', 'wire')
    )
    # the loop's targets, each printed with a verdict; those of the one-process robot, the
    # baseline and the wire all measured (a quick run's wire may miss DDS's latency, and
    # a quick two-process run may see no settled wheel step)
    targets = data['loop_targets']
    assert [t['label'] for t in targets] == [t.label for t in _targets()]
    assert all(t['verdict'] in ('PASS', 'MISS', 'n/a') for t in targets), targets
    measured = [t for t in targets if t['label'].startswith(
        ('robot CPU', 'tick duration', 'period error', 'two-process', 'wire gaps'))]
    assert len(measured) == 5
    assert all(t['verdict'] in ('PASS', 'MISS') for t in measured), measured
    for target in targets:
        assert any(line.startswith(f'| {target["label"]} |') for line in table_lines)
    # the loop's stages that rows look up by name are the running robot's
    by_key = {r['key']: r for r in data['rows']}
    for key in ('cpu.tick.feedback', 'cpu.tick.imu', 'cpu.tick.commands', 'cpu.tick.chassis'):
        assert by_key[key]['median'] is not None, key


def _targets():
    return bench_module('loop_targets').TARGETS


def test_profile_mode_profiles_every_busy_thread_of_the_robot(tmp_path):
    stdout = _run_bench(tmp_path, '--profile', '1')
    profiled = {line.split(':')[0] for line in stdout.splitlines() if 'CPU (profiled)' in line}
    # the loop (which also reads the serial ports) and the edge's publishers
    assert {'can-scheduler', 'can_bridge-publish', 'rm_robot-publish'} <= profiled, stdout
    assert list(tmp_path.glob('logs-*/profile_can-scheduler.prof'))


def test_profile_mode_with_only_split_profiles_both_processes(tmp_path):
    stdout = _run_bench(tmp_path, '--only', 'split', '--profile', '1')
    profiled = {line.split(':')[0] for line in stdout.splitlines() if 'CPU (profiled)' in line}
    # each process's loop: the bridge's CAN loop and rm_robot's own plugin loop
    assert {'bridge/can-scheduler', 'host/rm_robot-loop'} <= profiled, stdout
    assert list(tmp_path.glob('logs-*/host/profile_rm_robot-loop.prof'))
