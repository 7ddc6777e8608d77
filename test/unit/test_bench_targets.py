"""The bench's target table: a value next to its bound is printed so the two differ."""

import importlib
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _loop_targets():
    # bench/ is a package at the repository root, which is not on the test path
    sys.path.insert(0, str(ROOT))
    try:
        return importlib.import_module('bench.loop_targets')
    finally:
        sys.path.remove(str(ROOT))


def _line(table, label):
    (line,) = [line for line in table.splitlines() if line.startswith(f'| {label} |')]
    return line


def test_a_value_that_would_read_as_its_bound_gets_the_digits_that_tell_them_apart():
    targets = _loop_targets()
    rows = [
        {'key': 'cpu.rate.scheduler', 'values': [998.6, 999.46, 983.99]},
        {'key': 'wire.rate', 'values': [997.64, 990.37, 996.01]},
        {'key': 'sched.missed', 'values': [0.096, 0.1, 0.104]},
    ]
    table = targets.format_targets(targets.evaluate_targets(rows))
    ticks = _line(table, 'scheduler ticks/s, one process (make run)')
    assert '| 998.6 (984-999.5) | >= 999 | MISS |' in ticks
    wire = _line(table, 'from the wire: wheel group frames per second (make run)')
    assert '| 996 (990-998) | >= 995 | PASS |' in wire  # far enough: printed as always
    missed = _line(table, 'missed deadlines [%], one process')
    assert '| 0.10 (0.096-0.104) | < 0.10 | MISS |' in missed  # at the bound: as always


def test_the_docs_table_has_no_before_column():
    from bench.loop_targets import evaluate_targets, format_targets

    rows = [{'key': 'cpu.rate.scheduler', 'values': [999.5, 1000.0, 999.8]}]
    table = format_targets(evaluate_targets(rows), with_before=False)
    assert table.splitlines()[0] == '| metric | median (min-max) | target | result |'
    assert '| scheduler ticks/s, one process (make run) | 1000 (1000-1000) | >= 999 | PASS |' \
        in table
