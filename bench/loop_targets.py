"""The loop's targets (issue #48): each a ratio against a reference of the same run.

Absolute times drift by 2x between machines and by the hour on one, so every target
divides a figure of the robot by one measured in the same run, run by run (runs are
interleaved, so run i of every measurement shares its hour): the bare 1 kHz sleeper's
gaps and period error, the EventsExecutor timer loop of the same actuators, the loop's own
period, DDS's one-way latency of the same command messages, the robot in one process.

*Before* is what ``make bench`` gave on main 8a56e03 (3 runs, median, issue #48); *now*
the median of this run's ratios. The verdict compares the median with the target.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from typing import Any

from bench.report import _OPS, _fmt

PERIOD_US = 1000.0  # the loop's period at 1 kHz [µs]


@dataclass(frozen=True)
class Target:
    """One line: (row - minus) / per * scale, run by run, against a bound."""

    label: str
    key: str
    before: str
    op: str
    bound: float
    per: str | None = None  # divide by this row, run by run
    minus: str | None = None  # subtract this row first, run by run
    scale: float = 1.0


TARGETS: tuple[Target, ...] = (
    Target('wire gaps over 1.5 ms, robot / bare sleeper (make run)', 'wire.gaps', '2.4',
           '<=', 1.0, per='wire.canary.gaps'),
    Target('robot CPU streaming / EventsExecutor timer loop of its actuators',
           'cpu.load.host_bridge', '2.6', '<=', 1.0, per='bl.evt.cpu'),
    Target('tick duration p99 / period', 'sched.tick.p99', '0.98', '<=', 0.3,
           scale=1.0 / PERIOD_US),
    Target('command -> first frame of the new mode, median - DDS one-way latency [periods]',
           'wire.delay.median', '~1.5', '<=', 0.5, minus='wire.dds.median',
           scale=1000.0 / PERIOD_US),
    Target('period error p99 / bare sleeper p99', 'sched.p99', '0.40', '<=', 0.5,
           per='sched.canary.p99'),
    Target('two-process CPU / one-process CPU (robot without the simulator)',
           'split.cpu.host_bridge', '1.9', '<=', 1.3, per='cpu.load.host_bridge'),
)


def _ratio(value: float | None, minus: float | None, per: float | None, t: Target
           ) -> float | None:
    if value is None or (t.minus is not None and minus is None):
        return None
    if t.minus is not None:
        value -= minus
    if t.per is not None:
        if per is None:
            return None
        if per == 0:  # the reference saw none: equal when the robot saw none either
            return 1.0 if value == 0 else math.inf
        value /= per
    return value * t.scale


def evaluate_targets(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each target's median over runs (and min, max) from the evaluated rows, verdict."""
    by_key = {r['key']: r for r in rows}

    def values(key: str | None, n: int) -> list[float | None]:
        got = list(by_key.get(key, {}).get('values', [])) if key else []
        return (got + [None] * n)[:n]

    out = []
    for t in TARGETS:
        mine = list(by_key.get(t.key, {}).get('values', []))
        n = len(mine)
        ratios = [_ratio(v, m, d, t) for v, m, d in
                  zip(mine, values(t.minus, n), values(t.per, n), strict=True)]
        numbers = [v for v in ratios if v is not None and not math.isnan(v)]
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
            "**The loop's targets, ratios against references of this run (before: main 8a56e03)**",
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
