"""The control loop's targets (issue #11): before, now and target, one line each.

The *before* column holds what ``make bench`` measured on this 2-core VM on 2026-11-24,
before the robot ran its plugins in the CAN loop and its simulator in a process of its
own (3 runs, median; docs/PERFORMANCE.md has the context). *Now* is the median of this
run's rows (bench.report); a ratio row divides two of them run by run. The verdict
compares the median with the target.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from typing import Any

from bench.report import _OPS, CPU_TARGET_PCT, _fmt


@dataclass(frozen=True)
class Target:
    """One line: a row of bench.report (or the ratio of two), before, target."""

    label: str
    key: str
    before: str
    op: str
    bound: float
    per: str | None = None  # divide by this row, run by run


TARGETS: tuple[Target, ...] = (
    Target('scheduler ticks/s, one process (make run)', 'cpu.rate.scheduler', '855', '>=', 999),
    Target('scheduler ticks/s, two processes', 'split.rate.scheduler', '961', '>=', 999),
    Target('missed deadlines [%], one process', 'sched.missed', '14', '<', 0.1),
    Target('missed deadlines [%], two processes', 'split.missed', '3.9', '<', 0.1),
    Target('period error p99 / bare sleeper p99, one process', 'sched.p99', '3.1-4.7', '<=',
           1.5, per='sched.canary.p99'),
    Target('period error p99 / bare sleeper p99, two processes', 'split.p99', '1.2-1.8', '<=',
           1.5, per='split.canary.p99'),
    Target('/vel_cmd -> wheel frame p99 [ms], one process', 'lat.wheel.p99', '24', '<', 3.0),
    Target('/vel_cmd -> wheel frame p99 [ms], two processes', 'split.lat.wheel.p99', '6.3', '<',
           3.0),
    Target('/gimbal_cmd -> yaw frame p99 [ms], one process', 'lat.yaw.p99', '6.7', '<', 3.0),
    Target('/gimbal_cmd -> yaw frame p99 [ms], two processes', 'split.lat.yaw.p99', '6.9', '<',
           3.0),
    Target('CPU of the robot without the simulator, streaming [% of a core], one process',
           'cpu.load.process', '57', '<', CPU_TARGET_PCT),
    Target('CPU of the robot without the simulator, streaming [% of a core], two processes',
           'split.cpu.host_bridge', '71', '<', CPU_TARGET_PCT),
    Target('from the wire: wheel group frames per second (make run)', 'wire.rate', '901', '>=',
           995.0),
    Target('from the wire: gaps over 1.5 ms [%] (make run)', 'wire.gaps', '13', '<', 0.5),
    Target('from the wire: command -> new mode, worst of the steps [ms] (make run)',
           'wire.delay.max', '17', '<', 3.0),
)


def evaluate_targets(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each target's median over runs (and min, max) from the evaluated rows, verdict."""
    by_key = {r['key']: r for r in rows}
    out = []
    for t in TARGETS:
        values = list(by_key.get(t.key, {}).get('values', []))
        if t.per is not None:
            divisors = by_key.get(t.per, {}).get('values', [])
            values = [
                v / d if v is not None and d else None
                for v, d in zip(values, divisors, strict=False)
            ]
        numbers = [v for v in values if v is not None and not math.isnan(v)]
        median = statistics.median(numbers) if numbers else None
        verdict = 'n/a' if median is None else (
            'PASS' if _OPS[t.op](median, t.bound) else 'MISS'
        )
        out.append({
            'label': t.label, 'before': t.before,
            'median': median, 'min': min(numbers, default=None), 'max': max(numbers, default=None),
            'target': f'{t.op} {_fmt(t.bound)}', 'bound': t.bound, 'verdict': verdict,
        })
    return out


def _fmt_beside(x: float | None, bound: float) -> str:
    """x as the tables print it, with more digits while it would read as the bound.

    998.6 ticks/s would print as 999 beside a target of >= 999 and a MISS.
    """
    text = _fmt(x)
    if x is None or x == bound or text != _fmt(bound):
        return text
    for digits in range(1, 7):
        text = f'{x:.{digits}f}'
        if text != f'{bound:.{digits}f}':
            break
    return text


def format_targets(evaluated: list[dict[str, Any]], *, with_before: bool = True) -> str:
    """The lines as a Markdown table (without the *before* column for docs/PERFORMANCE.md)."""
    if with_before:
        lines = [
            '**Control loop targets (before: 2026-11-24, 3 runs, median)**',
            '',
            '| metric | before | now median (min-max) | target | result |',
            '|---|---|---|---|---|',
        ]
    else:
        lines = ['| metric | median (min-max) | target | result |', '|---|---|---|---|']
    for e in evaluated:
        shown = [_fmt_beside(e[k], e['bound']) for k in ('median', 'min', 'max')]
        now = f'{shown[0]} ({shown[1]}-{shown[2]})' if e['median'] is not None else 'n/a'
        before = f' {e["before"]} |' if with_before else ''
        lines.append(f'| {e["label"]} |{before} {now} | {e["target"]} | {e["verdict"]} |')
    return '\n'.join(lines)
