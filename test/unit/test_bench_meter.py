"""The meter's table: reference units, µs at the reference, new / old, absent stages."""

from support.bench import bench_module


def _meter():
    return bench_module('meter')


def _run(reference_ns, stages, loop_ns, layout='ordered', rounds=1):
    """A run of rounds alike: 1000 ticks each, stages and loop tick [ns per round]."""
    rows = {**stages, 'loop_tick_ns': loop_ns, 'publish_states_ns': 0, 'world_step_ns': 0}
    return {
        'layout': layout, 'wrapper_ns': 0.0,
        'rounds': [{'reference_ns': reference_ns, 'ticks': 1000, 'rows_ns': dict(rows),
                    'stage_calls': 1000 * len(stages)} for _ in range(rounds)],
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


def test_medians_over_every_round_and_the_meters_own_reads_kept_apart():
    meter = _meter()
    runs = [_run(1_000_000, {'send': ns}, ns) for ns in (10_000_000, 30_000_000, 20_000_000)]
    runs[0]['rounds'].append(dict(runs[0]['rounds'][0], reference_ns=500_000))  # 20 units
    summary = meter.summarise(runs)
    assert summary['units']['send'] == 20.0 and summary['rounds'] == 4
    # 1 µs of the meter's own per stage call: 1 µs a tick of the 20 µs tick is not the rest
    run = _run(1_000_000, {'send': 15_000_000}, 20_000_000)
    run['wrapper_ns'] = 1000.0
    units = meter.summarise([run])['units']
    assert units['meter_ns'] == 1.0 and units['rest_ns'] == 4.0
