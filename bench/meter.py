"""The lockstep CPU meter: what each part of the loop costs, in one A/B run.

    python bench/meter.py                         # this checkout, 3 runs
    python bench/meter.py --against 8a56e03       # and that commit, runs interleaved
    make meter METER_ARGS='--against 8a56e03'

Each run is a process of its own (bench/meter_child.py) that steps the standard robot of
one checkout in lockstep, streaming the bench's commands, and times every component of
the loop on the thread's CPU clock, normalised by a fixed reference workload timed in the
same process. With ``--against REV`` that commit is cloned into the cache
(``~/.cache/rm_ros2/meter/<sha>``), set up with its own ``scripts/setup.sh`` once, and its
runs alternate with this checkout's, so both see the same machine. The table gives each
component's CPU per tick in reference units (thousandths of the reference workload),
median over the rounds of all runs (each round against the reference timed just before
it), and new / old.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
CHILD = ROOT / 'bench' / 'meter_child.py'
CACHE = Path(os.environ.get('XDG_CACHE_HOME', Path.home() / '.cache')) / 'rm_ros2' / 'meter'

#: rows that are not one stage, (key, label): the tick's, after its stages; the others
#: after the message callbacks
TICK_ROWS = (
    ('loop_tick_ns', 'whole loop tick'),
    ('meter_ns', "  the meter's own clock reads around the stages (estimated)"),
    ('rest_ns', '  rest of the tick (not a stage: after-tick calls; the old update, pack, send)'),
)
OTHER_ROWS = (
    ('publish_states_ns', 'state messages (edge thread, at its rate)'),
    ('world_step_ns', 'simulator step (not the robot)'),
)
_NOT_STAGES = {k for k, _ in TICK_ROWS + OTHER_ROWS}
_MESSAGES = 'message callbacks'


def log(text: str) -> None:
    print(f'[meter] {text}', file=sys.stderr, flush=True)


def prepare(rev: str) -> Path:
    """A set-up checkout of rev in the cache (cloned and built on first use)."""
    sha = subprocess.run(
        ['git', '-C', str(ROOT), 'rev-parse', '--verify', f'{rev}^{{commit}}'],
        check=True, capture_output=True, text=True,
    ).stdout.strip()
    checkout = CACHE / sha
    if not (checkout / '.git').exists():
        CACHE.mkdir(parents=True, exist_ok=True)
        log(f'cloning {sha[:12]} into {checkout}')
        subprocess.run(['git', 'clone', '--quiet', '--no-checkout', str(ROOT), str(checkout)],
                       check=True)
        subprocess.run(['git', '-C', str(checkout), 'checkout', '--quiet', sha], check=True)
    setup_log = checkout / 'meter-setup.log'
    log(f'setting up {sha[:12]} (its own scripts/setup.sh; log {setup_log})')
    with setup_log.open('w') as out:
        done = subprocess.run([str(checkout / 'scripts' / 'setup.sh')], stdout=out,
                              stderr=subprocess.STDOUT, cwd=checkout, check=False)
    if done.returncode:
        raise RuntimeError(f'setting up {sha[:12]} failed; see {setup_log}')
    return checkout


def run_child(checkout: Path, ticks: int, rounds: int, domain_id: int) -> dict[str, Any]:
    """One run of the child in checkout's environment; its JSON result."""
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               ROS_DOMAIN_ID=str(domain_id))
    env.pop('PYTHONPATH', None)  # the checkout's environment, not ours
    done = subprocess.run(
        [str(checkout / 'scripts' / 'with_env.sh'), 'python', str(CHILD),
         '--checkout', str(checkout), '--ticks', str(ticks), '--rounds', str(rounds)],
        cwd=checkout, env=env, capture_output=True, text=True, check=False,
    )
    lines = done.stdout.strip().splitlines()
    if done.returncode or not lines:
        raise RuntimeError(f'meter run in {checkout} failed ({done.returncode}):\n'
                           f'{done.stderr[-3000:]}')
    return json.loads(lines[-1])


def per_tick(rnd: dict[str, Any], wrapper_ns: float) -> dict[str, float]:
    """One round's CPU per tick, each row in reference units [thousandths of its reference]."""
    scale = 1000.0 / (rnd['ticks'] * rnd['reference_ns'])
    rows = {name: ns * scale for name, ns in rnd['rows_ns'].items()}
    stage_ns = sum(ns for name, ns in rnd['rows_ns'].items()
                   if name not in _NOT_STAGES and not name.startswith(_MESSAGES))
    # the meter's clock reads around each stage are in the tick but no stage's
    meter_ns = wrapper_ns * rnd['stage_calls']
    rows['meter_ns'] = meter_ns * scale
    rows['rest_ns'] = (rnd['rows_ns']['loop_tick_ns'] - stage_ns - meter_ns) * scale
    return rows


def summarise(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Medians over every round of every run: per-tick costs in reference units."""
    rows = [per_tick(rnd, r.get('wrapper_ns', 0.0)) for r in results for rnd in r['rounds']]
    names = list(dict.fromkeys(name for r in rows for name in r))
    ref_us = statistics.median(rnd['reference_ns'] for r in results for rnd in r['rounds']) / 1e3
    med = {n: statistics.median(r[n] for r in rows if n in r) for n in names}
    return {'units': med, 'reference_us': ref_us, 'runs': len(results), 'rounds': len(rows),
            'layout': results[0]['layout']}


def _row_names(sides: list[dict[str, Any]]) -> list[tuple[str, str]]:
    names = list(dict.fromkeys(n for s in sides for n in s['units'] if n not in _NOT_STAGES))
    stages = [(n, f'  {n}') for n in names if not n.startswith(_MESSAGES)]
    messages = [(n, n) for n in names if n.startswith(_MESSAGES)]
    return stages + list(TICK_ROWS) + messages + list(OTHER_ROWS)


def format_table(new: dict[str, Any], old: dict[str, Any] | None, new_name: str,
                 old_name: str | None) -> str:
    """A Markdown table: per-tick cost in reference units (and µs at the median reference)."""
    sides = [new] + ([old] if old else [])
    head = f'| component | {new_name} [ref/1000] | µs |'
    rule = '|---|---:|---:|'
    if old:
        head += f' {old_name} [ref/1000] | µs | new / old |'
        rule += '---:|---:|---:|'
    lines = [head, rule]
    for key, label in _row_names(sides):
        cells = []
        for side in sides:
            v = side['units'].get(key)
            if v is None:
                cells += ['—', '—']
            else:
                cells += [f'{v:.1f}', f'{v * side["reference_us"] / 1000:.1f}']
        if old:
            a, b = new['units'].get(key), old['units'].get(key)
            cells.append(f'{a / b:.2f}' if a is not None and b else '—')
        lines.append(f'| {label} | ' + ' | '.join(cells) + ' |')
    lines.append('')
    lines.append(' '.join(
        f'{name}: reference workload {s["reference_us"]:.0f} µs of CPU, {s["runs"]} runs '
        f'({s["rounds"]} rounds), '
        f'loop layout "{s["layout"]}".' for name, s in zip((new_name, old_name), sides,
                                                          strict=False)))
    return '\n'.join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='bench/meter.py', description=__doc__.split('\n\n')[0])
    parser.add_argument('--against', metavar='REV', help='a commit to compare with, side by side')
    parser.add_argument('--runs', type=int, default=3, help='runs per checkout (3)')
    parser.add_argument('--ticks', type=int, default=2000, help='ticks per round (2000)')
    parser.add_argument('--rounds', type=int, default=5, help='rounds per run (5)')
    parser.add_argument('--domain-id', type=int,
                        default=int(os.environ.get('BENCH_ROS_DOMAIN_ID', '91')))
    parser.add_argument('--json', type=Path, help='write the raw runs here')
    args = parser.parse_args(argv)
    if args.runs < 1 or args.ticks < 1 or args.rounds < 1:
        parser.error('--runs, --ticks and --rounds must be at least 1')
    old_checkout = prepare(args.against) if args.against else None
    new_runs: list[dict[str, Any]] = []
    old_runs: list[dict[str, Any]] = []
    for i in range(args.runs):
        # alternate which goes first, so a drift in the machine hits both alike
        order = [(ROOT, new_runs), (old_checkout, old_runs)]
        if i % 2:
            order.reverse()
        for checkout, runs in order:
            if checkout is None:
                continue
            log(f'run {i + 1}/{args.runs}: {checkout}')
            runs.append(run_child(checkout, args.ticks, args.rounds, args.domain_id))
    head = subprocess.run(['git', '-C', str(ROOT), 'rev-parse', '--short', 'HEAD'],
                          capture_output=True, text=True, check=False).stdout.strip()
    new = summarise(new_runs)
    old = summarise(old_runs) if old_runs else None
    print(f'lockstep CPU meter: {args.runs} runs x {args.rounds} rounds x {args.ticks} ticks, '
          'CPU per tick, median over rounds')
    print()
    print(format_table(new, old, f'{head or "this checkout"} (work tree)', args.against))
    if args.json:
        args.json.write_text(json.dumps({'new': new_runs, 'old': old_runs}, indent=1))
    return 0


if __name__ == '__main__':
    sys.exit(main())
