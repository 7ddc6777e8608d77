"""The meter's table: reference units, µs at the reference, new / old, absent stages."""

from support.bench import bench_module


def _meter():
    return bench_module('meter')


def _run(reference_ns, stages, loop_ns, layout='ordered'):
    return {
        'ticks': 1000, 'reference_ns': reference_ns, 'layout': layout,
        'loop_tick_ns': loop_ns, 'publish_states_ns': 0, 'world_step_ns': 0,
        'stages': {name: {'ns': ns, 'calls': 1000, 'worked': 1000} for name, ns in stages.items()},
    }


def test_costs_read_in_thousandths_of_the_reference_and_compare_side_by_side():
    meter = _meter()
    # new: 100 µs of feedback per tick at a 1 ms reference; old: 300 µs at 2 ms (a machine
    # twice as slow), and a stage the new loop no longer has
    new = meter.summarise([_run(1_000_000, {'feedback': 100_000_000}, 150_000_000)])
    old = meter.summarise([_run(2_000_000, {'feedback': 300_000_000, 'commands': 40_000_000},
                                400_000_000, 'inputs/outputs')])
    assert new['units']['feedback'] == 100.0 and old['units']['feedback'] == 150.0
    assert new['units']['rest_ns'] == 50.0 and old['units']['rest_ns'] == 30.0
    table = meter.format_table(new, old, 'new', 'old')
    rows = {line.split('|')[1].strip(): line for line in table.splitlines()[2:] if '|' in line}
    assert rows['feedback'] == '|   feedback | 100.0 | 100.0 | 150.0 | 300.0 | 0.67 |'
    assert rows['commands'] == '|   commands | — | — | 20.0 | 40.0 | — |'
    assert rows['whole loop tick'].endswith('| 0.75 |')  # 150 units against 200


def test_medians_over_runs():
    meter = _meter()
    runs = [_run(1_000_000, {'send': ns}, ns) for ns in (10_000_000, 30_000_000, 20_000_000)]
    assert meter.summarise(runs)['units']['send'] == 20.0
