"""The lockstep CPU meter runs the real robot and accounts for every tick's CPU.

No number is judged (this machine is shared): only that each stage of the loop is timed
where it works, at its rate, and that the parts add up within the whole.
"""

import json
import os
import pathlib
import sys

import pytest
from support.ros import start_process

pytestmark = [pytest.mark.ros, pytest.mark.slow]

ROOT = pathlib.Path(__file__).resolve().parents[2]
TICKS = 300
TIMEOUT = 240.0  # [s] ~15 s on a quiet machine


def test_the_meter_times_every_stage_of_the_standard_robot(tmp_path):
    raw = tmp_path / 'meter.json'
    command = [sys.executable, str(ROOT / 'bench' / 'meter.py'), '--runs', '1', '--rounds', '2',
               '--ticks', str(TICKS), '--json', str(raw),
               '--domain-id', os.environ['ROS_DOMAIN_ID']]
    proc = start_process(command, cwd=ROOT)
    stdout, stderr = proc.communicate(timeout=TIMEOUT)
    assert proc.returncode == 0, stdout[-3000:] + stderr[-3000:]
    (run,) = json.loads(raw.read_text())['new']
    stages = run['stages']
    ticks = 2 * TICKS
    assert run['ticks'] == ticks and run['layout'] == 'ordered'
    # each stage timed in every tick, and worked at its plugin's rate
    assert all(s['calls'] == ticks for s in stages.values()), stages
    assert stages['feedback']['worked'] == ticks
    assert stages['send']['worked'] == ticks
    assert abs(stages['plugin chassis']['worked'] - ticks / 5) <= 1  # 200 Hz
    # 250 Hz, and a run for each new command between (100 Hz)
    assert ticks / 4 - 1 <= stages['plugin gimbal']['worked'] <= ticks / 4 + ticks / 10 + 1
    # the parts within the whole: stages within the loop tick, the tick and the simulator
    # within what the harness ran
    assert 0 < sum(s['ns'] for s in stages.values()) <= run['loop_tick_ns']
    assert run['loop_tick_ns'] + run['world_step_ns'] <= run['harness_step_ns']
    assert run['publish_states_calls'] == ticks // 5  # the edge's 200 Hz
    assert run['reference_ns'] > 0
    # round by round, the same ledgers
    assert [r['ticks'] for r in run['rounds']] == [TICKS, TICKS]
    assert sum(r['rows_ns']['loop_tick_ns'] for r in run['rounds']) == run['loop_tick_ns']
    for label in ('plugin chassis', 'feedback', 'send', 'whole loop tick', 'state messages'):
        assert any(line.startswith(f'|   {label} |') or line.startswith(f'| {label}')
                   for line in stdout.splitlines()), label
