"""The bench's target table: ratios run by run, printed so a value and its bound differ."""

import math

import pytest
from support.bench import bench_module


def _loop_targets():
    return bench_module('loop_targets')


def _line(table, label):
    (line,) = [line for line in table.splitlines() if line.startswith(f'| {label} |')]
    return line


def _by_label(evaluated, start):
    (e,) = [e for e in evaluated if e['label'].startswith(start)]
    return e


def test_each_ratio_divides_run_by_run_with_its_own_run_of_the_reference():
    targets = _loop_targets()
    rows = [
        {'key': 'cpu.load.host_bridge', 'values': [40.0, 60.0, 30.0]},
        {'key': 'bl.evt.cpu', 'values': [20.0, 60.0, 10.0]},
        {'key': 'split.cpu.host_bridge', 'values': [48.0, 60.0, 45.0]},
    ]
    evaluated = targets.evaluate_targets(rows)
    cpu = _by_label(evaluated, 'robot CPU streaming / EventsExecutor')
    # 2.0, 1.0, 3.0 run by run (the ratio of the medians would be 40 / 20 = 2.0 too,
    # but min and max tell them apart)
    assert (cpu['median'], cpu['min'], cpu['max']) == (2.0, 1.0, 3.0)
    assert cpu['verdict'] == 'MISS'
    split = _by_label(evaluated, 'two-process CPU')
    assert (split['median'], split['min'], split['max']) == (1.2, 1.0, 1.5)
    assert split['verdict'] == 'PASS'
    # rows the run did not measure: no verdict
    assert _by_label(evaluated, 'wire gaps')['verdict'] == 'n/a'


def test_a_difference_in_periods_and_a_reference_that_saw_nothing():
    targets = _loop_targets()
    rows = [
        {'key': 'wire.delay.median', 'values': [1.9, 1.2]},
        {'key': 'wire.dds.median', 'values': [1.5, None]},
        {'key': 'sched.tick.p99', 'values': [250.0, 400.0]},
        {'key': 'wire.gaps', 'values': [0.0, 0.3]},
        {'key': 'wire.canary.gaps', 'values': [0.0, 0.0]},
    ]
    evaluated = targets.evaluate_targets(rows)
    delay = _by_label(evaluated, 'command -> first frame')
    assert math.isclose(delay['median'], 0.4) and delay['min'] == delay['max']  # one run
    assert delay['verdict'] == 'PASS'
    tick = _by_label(evaluated, 'tick duration p99 / period')
    assert (tick['min'], tick['max']) == (0.25, 0.4)
    gaps = _by_label(evaluated, 'wire gaps')
    # none against none is as good as the sleeper; some against none is worse than any ratio
    assert (gaps['min'], gaps['max']) == (1.0, math.inf)


def test_a_value_that_would_read_as_its_bound_gets_the_digits_that_tell_them_apart():
    targets = _loop_targets()
    rows = [
        {'key': 'sched.p99', 'values': [50.2, 50.3, 49.6]},
        {'key': 'sched.canary.p99', 'values': [100.0, 100.0, 100.0]},
    ]
    table = targets.format_targets(targets.evaluate_targets(rows))
    line = _line(table, 'period error p99 / bare sleeper p99')
    assert '| 0.502 (0.496-0.503) | - | <= 0.50 | MISS |' in line


def test_the_docs_table_has_no_before_column():
    targets = _loop_targets()
    rows = [{'key': 'sched.tick.p99', 'values': [200.0, 210.0, 190.0]}]
    table = targets.format_targets(targets.evaluate_targets(rows), with_before=False)
    assert table.splitlines()[0] == (
        '| metric | median (min-max) | floor (min-max) | target | result |'
    )
    assert '| tick duration p99 / period | 0.20 (0.19-0.21) | - | <= 0.30 | PASS |' in table


def test_a_floor_is_the_same_ratio_for_the_loop_with_only_its_actuators_run_by_run():
    targets = _loop_targets()
    rows = [
        {'key': 'sched.tick.p99', 'values': [800.0, 900.0, 850.0]},
        {'key': 'bl.thread.tick.p99', 'values': [350.0, 230.0, 310.0]},
        {'key': 'cpu.load.host_bridge', 'values': [40.0, 60.0, 30.0]},
        {'key': 'bl.thread.cpu', 'values': [22.0, 30.0, 9.0]},
        {'key': 'bl.evt.cpu', 'values': [20.0, 60.0, 10.0]},
    ]
    evaluated = targets.evaluate_targets(rows)
    tick = _by_label(evaluated, 'tick duration p99 / period')
    assert (tick['floor'], tick['floor_min'], tick['floor_max']) == pytest.approx(
        (0.31, 0.23, 0.35))
    cpu = _by_label(evaluated, 'robot CPU streaming / EventsExecutor')
    # 1.1, 0.5, 0.9: each run's loop against the same run's EventsExecutor loop
    assert (cpu['floor'], cpu['floor_min'], cpu['floor_max']) == pytest.approx((0.9, 0.5, 1.1))
    table = targets.format_targets(evaluated)
    # the floor printed beside the target it sits above
    assert '| 0.85 (0.80-0.90) | 0.31 (0.23-0.35) | <= 0.30 | MISS |' in _line(
        table, 'tick duration p99 / period')
    # a line without a floor, or a floor the run did not measure, shows a dash
    assert '| - |' in _line(table, 'period error p99 / bare sleeper p99')
