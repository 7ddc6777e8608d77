"""The loop's targets (issue #48): each a ratio against a reference of the same run.

Absolute times drift by 2x between machines and by the hour on one, so every target
divides a figure of the robot by one measured in the same run, run by run (runs are
interleaved, so run i of every measurement shares its hour): the bare 1 kHz sleeper's
gaps and period error, the EventsExecutor timer loop of the same actuators, the loop's own
period, DDS's one-way latency of the same command messages, the robot in one process.

*Before* is what ``make bench`` gave on main 8a56e03 (3 runs, median, issue #48); *now*
the median of this run's ratios. The verdict compares the median with the target.

Where the bench measures it, a *floor* is the same ratio for the loop carrying only its
actuators (the baseline's scheduler thread: the same hardware tick with no plugin, IMU port
or command), in the same run: what the robot would reach if all it does beyond its motors
cost nothing. A target below its floor cannot be met by cutting the robot's own work.
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
    floor: str | None = None  # the same ratio of the loop with only its actuators: this row
    floor_per: str | None = None  # ... divided by this one


TARGETS: tuple[Target, ...] = (
    Target('wire gaps over 1.5 ms, robot / bare sleeper (make run)', 'wire.gaps', '2.4',
           '<=', 1.0, per='wire.canary.gaps'),
    Target('robot CPU streaming / EventsExecutor timer loop of its actuators',
           'cpu.load.host_bridge', '2.6', '<=', 1.0, per='bl.evt.cpu',
           floor='bl.thread.cpu', floor_per='bl.evt.cpu'),
    Target('tick duration p99 / period', 'sched.tick.p99', '0.98', '<=', 0.3,
           scale=1.0 / PERIOD_US, floor='bl.thread.tick.p99'),
    Target('command -> first frame of the new mode, median - DDS one-way latency [periods]',
           'wire.delay.median', '~1.5', '<=', 0.5, minus='wire.dds.median',
           scale=1000.0 / PERIOD_US),
    Target('period error p99 / bare sleeper p99', 'sched.p99', '0.40', '<=', 0.5,
           per='sched.canary.p99'),
    Target('two-process CPU / one-process CPU (robot without the simulator)',
           'split.cpu.host_bridge', '1.9', '<=', 1.3, per='cpu.load.host_bridge'),
)


def _ratio(value: float | None, minus: float | None, per: float | None, scale: float,
           *, divided: bool, subtracted: bool) -> float | None:
    """(value - minus) / per * scale, each step only where the line asks for it."""
    if value is None or (subtracted and minus is None):
        return None
    if subtracted:
        value -= minus
    if divided:
        if per is None:
            return None
        if per == 0:  # the reference saw none: equal when the robot saw none either
            return 1.0 if value == 0 else math.inf
        value /= per
    return value * scale


def _spread(ratios: list[float | None]) -> tuple[float | None, float | None, float | None]:
    """Median, min and max of the ratios the runs gave."""
    numbers = [v for v in ratios if v is not None and not math.isnan(v)]
    median = statistics.median(numbers) if numbers else None
    return median, min(numbers, default=None), max(numbers, default=None)


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
        ratios = [
            _ratio(v, m, d, t.scale, divided=t.per is not None, subtracted=t.minus is not None)
            for v, m, d in zip(mine, values(t.minus, n), values(t.per, n), strict=True)
        ]
        median, low, high = _spread(ratios)
        verdict = 'n/a' if median is None else (
            'PASS' if _OPS[t.op](median, t.bound) else 'MISS'
        )
        floors: list[float | None] = []
        if t.floor is not None:
            base = list(by_key.get(t.floor, {}).get('values', []))
            floors = [
                _ratio(v, None, d, t.scale, divided=t.floor_per is not None, subtracted=False)
                for v, d in zip(base, values(t.floor_per, len(base)), strict=True)
            ]
        floor, floor_low, floor_high = _spread(floors)
        out.append({
            'label': t.label, 'before': t.before,
            'median': median, 'min': low, 'max': high,
            'floor': floor, 'floor_min': floor_low, 'floor_max': floor_high,
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


def _shown(e: dict[str, Any], median: str, low: str, high: str) -> str:
    """'median (min-max)' of e's keys, or 'n/a'."""
    if e[median] is None:
        return 'n/a'
    shown = [_fmt_beside(e[k], e['bound']) for k in (median, low, high)]
    return f'{shown[0]} ({shown[1]}-{shown[2]})'


def format_targets(evaluated: list[dict[str, Any]], *, with_before: bool = True) -> str:
    """The lines as a Markdown table (without the *before* column for docs/PERFORMANCE.md)."""
    if with_before:
        lines = [
            "**The loop's targets, ratios against references of this run (before: main 8a56e03)**",
            '',
            '| metric | before | now median (min-max) | floor (min-max) | target | result |',
            '|---|---|---|---|---|---|',
        ]
    else:
        lines = ['| metric | median (min-max) | floor (min-max) | target | result |',
                 '|---|---|---|---|---|']
    for e in evaluated:
        now = _shown(e, 'median', 'min', 'max')
        floor = _shown(e, 'floor', 'floor_min', 'floor_max') if e.get('floor') is not None else '-'
        before = f' {e["before"]} |' if with_before else ''
        lines.append(
            f'| {e["label"]} |{before} {now} | {floor} | {e["target"]} | {e["verdict"]} |'
        )
    return '\n'.join(lines)
