"""Run the rm_ros2 benchmarks and print the result table: ``make bench``.

    python bench/run.py                 # everything, 3 runs each (a few minutes)
    python bench/run.py --quick         # sub-second windows, 1 run (smoke test)
    python bench/run.py --only robot --only split --runs 5
    make bench BENCH_ARGS='--only throughput'

Prints machine facts and one table (min / median / max over runs, PASS/MISS against the
targets, CPU steal and load average beside each figure) and writes the whole result,
raw per-run data included, as JSON under bench/results/ (``--out`` elsewhere).

Network rule: this process and every process it starts use localhost-only DDS discovery
and the ROS domain of ``--domain-id`` (default ``$BENCH_ROS_DOMAIN_ID`` or 90, away from
the interactive 42). Other work on the machine skews timing: rerun when the load average
is low; the table shows the steal and load of every window.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import json
import os
import shlex
import signal
import sys
import time
import traceback
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

MEASUREMENTS = ('robot', 'throughput', 'baseline', 'split', 'wire')
DEFAULT_DOMAIN_ID = 90


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog='bench/run.py', description=__doc__.split('\n\n')[0])
    parser.add_argument('--quick', action='store_true', help='tiny windows, one run')
    parser.add_argument('--runs', type=int, default=None, help='runs per measurement (3)')
    parser.add_argument(
        '--only', action='append', choices=MEASUREMENTS, help='run only this (repeatable)'
    )
    parser.add_argument(
        '--domain-id',
        type=int,
        default=int(os.environ.get('BENCH_ROS_DOMAIN_ID', DEFAULT_DOMAIN_ID)),
        help='ROS_DOMAIN_ID of every ROS process of the bench',
    )
    parser.add_argument('--out', type=Path, default=ROOT / 'bench' / 'results')
    parser.add_argument('--plugins', default='', help='robot plugins subset, comma-separated')
    parser.add_argument(
        '--switch-interval-us',
        type=float,
        help='robot process: GIL switch interval after start-up (experiments)',
    )
    parser.add_argument(
        '--profile',
        type=float,
        metavar='SECONDS',
        help='only profile every robot thread under load (cProfile) and print the hot spots; '
        'with --only split, both processes of the split robot',
    )
    return parser.parse_args(argv)


def log(text: str) -> None:
    print(f'[bench] {text}', file=sys.stderr, flush=True)


def _stop_on_sigterm(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f'signal {signum}')  # so every child is closed on the way out


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    signal.signal(signal.SIGTERM, _stop_on_sigterm)
    # Network rule, before anything imports rclpy; children inherit it.
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ['ROS_DOMAIN_ID'] = str(args.domain_id)

    from bench import baseline, robot, throughput, wire_check
    from bench.doc_table import PAGES, write_table
    from bench.loop_targets import evaluate_targets, format_targets
    from bench.machine import Window, machine_facts
    from bench.report import ROWS, evaluate, format_table

    runs = args.runs or (1 if args.quick else 3)
    only = args.only or list(MEASUREMENTS)
    robot_plan = robot.QUICK_PLAN if args.quick else robot.RobotPlan()
    if args.plugins or args.switch_interval_us:
        robot_plan = dataclasses.replace(
            robot_plan, plugins=args.plugins, switch_interval_us=args.switch_interval_us
        )
    tp_plan = throughput.QUICK_PLAN if args.quick else throughput.ThroughputPlan()
    bl_plan = baseline.QUICK_PLAN if args.quick else baseline.BaselinePlan()
    wire_plan = wire_check.QUICK_PLAN if args.quick else wire_check.WirePlan()

    stamp = dt.datetime.now().strftime('%Y%m%d-%H%M%S')
    args.out.mkdir(parents=True, exist_ok=True)
    log_dir = args.out / f'logs-{stamp}'
    log_dir.mkdir(parents=True, exist_ok=True)
    if args.profile:
        profile = robot.profile_split if only == ['split'] else robot.profile
        return print_profile(profile(robot_plan, log_dir, args.profile), log_dir)
    facts = machine_facts()
    load_start = os.getloadavg()
    whole = Window()
    t_start = time.monotonic()
    log(
        f'{runs} run(s) of {", ".join(only)}; ROS_DOMAIN_ID={args.domain_id}, localhost only; '
        f'load average {load_start[0]:.2f}'
    )

    raw: dict[str, list[dict[str, Any]]] = {m: [] for m in MEASUREMENTS}
    notes: list[str] = []
    steps = {
        'robot': lambda i: robot.run_once(robot_plan, log_dir, str(i)),
        'throughput': lambda i: throughput.run_once(tp_plan),
        'baseline': lambda i: baseline.run_once(bl_plan),
        'split': lambda i: robot.run_split(robot_plan, log_dir, str(i)),
        'wire': lambda i: wire_check.run_once(wire_plan, log_dir, str(i)),
    }
    # Runs interleave the measurements, so a burst of steal or load hits all of them alike.
    for i in range(1, runs + 1):
        for name in only:
            t0 = time.monotonic()
            try:
                result = steps[name](i)
            except Exception as err:
                notes.append(f'{name} run {i} failed: {type(err).__name__}: {err}')
                log(notes[-1])
                traceback.print_exc(file=sys.stderr)
                continue
            notes += [f'{name} run {i}: {n}' for n in result.get('notes', [])]
            raw[name].append(result)
            log(
                f'run {i}/{runs}: {name} done in {time.monotonic() - t0:.1f} s '
                f'(load {os.getloadavg()[0]:.2f})'
            )

    overall = whole.close()
    evaluated = evaluate(ROWS, raw)
    command = 'python bench/run.py' + ''.join(f' {shlex.quote(a)}' for a in (argv or sys.argv[1:]))

    print()
    print(f'rm_ros2 benchmarks, {facts["date"]}')
    print(
        f'machine: {facts["cpu_model"]}, {facts["cores"]} cores'
        f'{" (virtual machine)" if facts["virtualised"] else ""}, Linux {facts["kernel"]}, '
        f'Python {facts["python"]}, rclpy {facts["rclpy"]}, python-can {facts["python-can"]}'
    )
    print(f'command: {command}; {runs} run(s) each; total {time.monotonic() - t_start:.0f} s')
    print(
        f'whole run: CPU steal {overall.steal_pct:.1f} %, machine busy {overall.busy_pct:.0f} %, '
        f'load average {load_start[0]:.2f} at start, {os.getloadavg()[0]:.2f} at end'
    )
    print('values: min / median / max over runs; PASS/MISS compares the median with the target')
    print()
    targets = evaluate_targets(evaluated)
    print(format_targets(targets))
    print()
    print(format_table(evaluated))
    if notes:
        print()
        print('notes:')
        for note in notes:
            print(f'- {note}')

    result_path = args.out / f'bench-{stamp}.json'
    result_path.write_text(
        json.dumps(
            {
                'machine': facts,
                'command': command,
                'runs': runs,
                'quick': args.quick,
                'domain_id': args.domain_id,
                'overall': {**overall.as_dict(), 'load_start': load_start},
                'rows': evaluated,
                'loop_targets': targets,
                'notes': notes,
                'raw': raw,
            },
            indent=1,
            default=str,
        )
    )
    print()
    shown = result_path.relative_to(ROOT) if result_path.is_relative_to(ROOT) else result_path
    print(f'results: {shown}')
    if not args.quick and args.only is None and args.runs is None and not args.plugins:
        # a full run is the page's latest table; a partial one would leave rows empty
        caption = (f'`make bench`, {runs} runs, median (min-max), commit {facts["commit"]}, '
                   f'{facts["cpu_model"]} ({facts["cores"]} cores), {facts["date"]}')
        table = format_targets(targets, with_before=False)
        for page in PAGES:
            write_table(ROOT / page, table, caption)
        print("README.md and docs/PERFORMANCE.md: their latest table is this run's")
    return 0 if all(raw[name] for name in only) else 1


def print_profile(profiles: dict[str, Any], log_dir: Path) -> int:
    for name, data in sorted(profiles.items(), key=lambda kv: -kv[1]['total_s']):
        print(f'\n{name}: {data["total_s"]:.3f} s CPU (profiled)')
        for row in data['top'][:12]:
            print(
                f'  {row["tottime_s"]:8.4f} s own {row["cumtime_s"]:8.4f} s cum '
                f'{row["ncalls"]:>8} calls  {row["function"]}'
            )
    print(f'\nfull profiles: {log_dir}/**/profile_*.txt')
    return 0


if __name__ == '__main__':
    sys.exit(main())
