"""The result table: one row per figure, min / median / max over runs, PASS/MISS.

Every row is declared in :data:`ROWS` (the smoke test checks that each one is printed).
A row's value is extracted from each run's raw result; the verdict compares the *median*
over runs with the target. Timing rows carry the CPU steal and the 1-minute load average
of their own measuring windows (median over runs; steal also its max).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from bench.stats import spread

Extract = Callable[[dict[str, Any]], float | None]
Windows = Callable[[dict[str, Any]], list[dict[str, Any]]]

SECTIONS = {
    'scheduler': '1. Scheduler at 1 kHz (standard robot on rm_sim, commands streaming at 100 Hz)',
    'latency': '2. Command -> first CAN frame with the new target (cross-process, CLOCK_MONOTONIC)',
    'cpu': '3. CPU, % of one core (one process: bridge + host + sim, split by thread)',
    'throughput': '4. Feedback decode + dispatch (bridge code, rigs without physics)',
    'baseline': '5. Same 1 kHz loop on an rclpy timer (standard robot actuators, same run)',
    'split': '6. Sections 1-3 again with can_bridge and rm_robot in two processes (rm_sim a third)',
    'wire': '7. From the wire: can0 log of bringup --sim, /chassis_cmd PASSIVE <-> RAW every 0.6 s',
}


@dataclass(frozen=True)
class Row:
    """One line of the table.

    Attributes:
        key: stable id (JSON, smoke test).
        section: key of :data:`SECTIONS`.
        label: what is shown.
        source: which raw result the row reads: ``robot``, ``throughput`` or ``baseline``.
        extract: run result -> value (None if absent).
        target: (comparison, bound) or None for information rows.
        windows: run result -> the measuring windows behind the value (steal, load).
    """

    key: str
    section: str
    label: str
    source: str
    extract: Extract
    target: tuple[str, float] | None = None
    windows: Windows | None = None


def _get(*path: Any) -> Extract:
    def extract(run: dict[str, Any]) -> float | None:
        node: Any = run
        for key in path:
            if isinstance(node, dict) and key in node:
                node = node[key]
            elif isinstance(node, list) and isinstance(key, int) and key < len(node):
                node = node[key]
            else:
                return None
        return float(node) if isinstance(node, int | float) else None

    return extract


def _phase(phase: str) -> Windows:
    return lambda run: [run[phase]['window']] if phase in run else []


def _sweep(motors: int) -> Extract:
    def extract(run: dict[str, Any]) -> float | None:
        for point in run.get('sweep', {}).get('points', []):
            if point['motors'] == motors:
                return point['cpu']['bridge_pct']
        return None

    return extract


def _sweep_windows(run: dict[str, Any]) -> list[dict[str, Any]]:
    return [p['window'] for p in run.get('sweep', {}).get('points', [])]


def _knee_windows(run: dict[str, Any]) -> list[dict[str, Any]]:
    return [p['window'] for p in run.get('knee', {}).get('points', [])]


def _at20k_window(run: dict[str, Any]) -> list[dict[str, Any]]:
    point = run.get('knee', {}).get('at_20k')
    return [point['window']] if point else []


def _variant(name: str) -> Windows:
    return lambda run: [run[name]['window']] if name in run else []


def _detected(run: dict[str, Any]) -> float | None:
    lat = run.get('latency')
    if not lat:
        return None
    steps = sum(v['steps'] - v['unsettled'] for v in lat.values())
    return 100.0 * sum(v['detected'] for v in lat.values()) / steps if steps else None


def _latency_windows(run: dict[str, Any]) -> list[dict[str, Any]]:
    return [run['load']['window']] if 'load' in run else []


def _rows(section: str, source: str, rows: tuple[tuple[Any, ...], ...]) -> tuple[Row, ...]:
    """Rows of one section and source: (key, label, extract, target, windows) each."""
    return tuple(Row(key, section, label, source, *rest) for key, label, *rest in rows)


_LOAD = _phase('load')
_IDLE = _phase('idle')
_ALL = _variant('scheduler_thread')
_STE = _variant('rclpy_single_threaded')
_EVT = _variant('rclpy_events')

ROWS: tuple[Row, ...] = (
    # 1. scheduler
    *_rows('scheduler', 'robot', (
        ('sched.p50', 'period error p50 [µs]',
         _get('load', 'scheduler', 'error_us', 'p50'), None, _LOAD),
        ('sched.p99', 'period error p99 [µs]',
         _get('load', 'scheduler', 'error_us', 'p99'), None, _LOAD),
        ('sched.canary.p99', '  same window, bare 1 kHz sleeper process (OS wake-up) p99 [µs]',
         _get('canary', 'error_us', 'p99'), None, _LOAD),
        ('sched.max', 'period error max [µs]',
         _get('load', 'scheduler', 'error_us', 'max'), None, _LOAD),
        ('sched.missed', 'missed deadlines [%]',
         _get('load', 'scheduler', 'missed_pct'), None, _LOAD),
        ('sched.tick.p99', 'tick duration (update + pack + send) p99 [µs]',
         _get('load', 'scheduler', 'tick_us', 'p99'), None, _LOAD),
        ('sched.simlock.p99', 'sim physics tick (holds the world lock sends wait for) p99 [µs]',
         _get('load', 'sim_tick_us', 'p99'), None, _LOAD),
    )),
    *_rows('scheduler', 'throughput', (
        ('sched.tick.alone', 'one tick alone on a thread, no contention [µs CPU]',
         _get('tick', 'us_per_tick'), None, None),
        ('sched.tick.slept', '  the same, each tick after a 0.9 ms sleep (as the loop) [µs CPU]',
         _get('tick_after_sleep', 'us_per_tick'), None, None),
    )),
    *_rows('scheduler', 'robot', (
        ('sched.idle.p99', 'idle robot: period error p99 [µs]',
         _get('idle', 'scheduler', 'error_us', 'p99'), None, _IDLE),
        ('sched.idle.missed', 'idle robot: missed deadlines [%]',
         _get('idle', 'scheduler', 'missed_pct'), None, _IDLE),
    )),
    # 2. latency
    *_rows('latency', 'robot', (
        ('lat.wheel.p50', '/vel_cmd -> wheel_fl current p50 [ms]',
         _get('latency', 'wheel_fl', 'total_ms', 'p50'), None, _latency_windows),
        ('lat.wheel.p99', '/vel_cmd -> wheel_fl current p99 [ms]',
         _get('latency', 'wheel_fl', 'total_ms', 'p99'), None, _latency_windows),
        ('lat.yaw.p50', '/gimbal_cmd -> yaw voltage p50 [ms]',
         _get('latency', 'yaw', 'total_ms', 'p50'), None, _latency_windows),
        ('lat.yaw.p99', '/gimbal_cmd -> yaw voltage p99 [ms]',
         _get('latency', 'yaw', 'total_ms', 'p99'), None, _latency_windows),
        ('lat.wheel.bridge', '  wheel: publish -> bridge applies, p50 [ms]',
         _get('latency', 'wheel_fl', 'to_bridge_ms', 'p50'), None, _latency_windows),
        ('lat.yaw.bridge', '  yaw: publish -> bridge applies, p50 [ms]',
         _get('latency', 'yaw', 'to_bridge_ms', 'p50'), None, _latency_windows),
        ('lat.wire.p99', '  wheel: bridge applies -> wire, p99 [ms]',
         _get('latency', 'wheel_fl', 'to_wire_ms', 'p99'), None, _latency_windows),
        ('lat.detected', 'settled steps seen on the wire [%]', _detected, None, None),
    )),
    # 3. cpu
    *_rows('cpu', 'robot', (
        ('cpu.load.host_bridge', 'host + bridge, streaming',
         _get('load', 'groups', 'host_bridge'), None, _LOAD),
        ('cpu.idle.host_bridge', 'host + bridge, idle',
         _get('idle', 'groups', 'host_bridge'), None, _IDLE),
        ('cpu.load.host', "  host: outbox + serial ports' threads (they only open the ports)",
         _get('load', 'groups', 'host'), None, _LOAD),
        ('cpu.load.bridge', '  bridge: the loop (plugins included) + publisher',
         _get('load', 'groups', 'bridge'), None, _LOAD),
        ('cpu.load.scheduler', '    of which the 1 kHz scheduler thread',
         _get('load', 'threads', 'can-scheduler'), None, _LOAD),
        ('cpu.load.ros', '  ROS: executor (main thread) + DDS, shared',
         _get('load', 'groups', 'ros_shared'), None, _LOAD),
        ('cpu.load.sim', 'sim: physics thread, streaming',
         _get('load', 'groups', 'sim'), None, _LOAD),
        (
            'cpu.load.projected',
            'host + bridge, streaming, every loop at its nominal rate (lower bound)',
            _get('load', 'projected', 'host_bridge'),
            None,
            _LOAD,
        ),
        ('cpu.tick.scheduler', '  CPU per tick: 1 kHz scheduler [µs]',
         _get('load', 'loops', 'can-scheduler', 'us_per_tick'), None, _LOAD),
        # the loop's input stages by their own names, each timed in the ticks where it had
        # work (docs/PERFORMANCE.md, "A tick is many small Python costs")
        ('cpu.tick.feedback', '  feedback stage (both buses, every tick), p50 [µs]',
         _get('load', 'components', 'feedback', 'p50_us'), None, _LOAD),
        ('cpu.tick.imu', '  IMU port stage in a tick that read the port, p50 [µs]',
         _get('load', 'components', 'imu port', 'p50_us'), None, _LOAD),
        ('cpu.tick.commands', '  commands stage in a tick with commands, p50 [µs]',
         _get('load', 'components', 'commands', 'p50_us'), None, _LOAD),
        ('cpu.tick.chassis', '  chassis plugin run in the loop (200 Hz), p50 [µs]',
         _get('load', 'components', 'plugin chassis', 'p50_us'), None, _LOAD),
        ('cpu.tick.gimbal', '  gimbal plugin run in the loop (250 Hz), p50 [µs]',
         _get('load', 'components', 'plugin gimbal', 'p50_us'), None, _LOAD),
        ('cpu.tick.shooter', '  shooter plugin run in the loop (200 Hz), p50 [µs]',
         _get('load', 'components', 'plugin shooter', 'p50_us'), None, _LOAD),
        ('cpu.tick.sim', '  CPU per tick: sim physics (1 kHz) [µs]',
         _get('load', 'loops', 'rm_sim-physics', 'us_per_tick'), None, _LOAD),
        ('cpu.rate.scheduler', 'scheduler ticks achieved, streaming [Hz]',
         _get('load', 'loops', 'can-scheduler', 'achieved_hz'), None, _LOAD),
        ('cpu.load.process', 'whole process (getrusage), streaming',
         _get('load', 'process_pct'), None, _LOAD),
    )),
    # 4. throughput
    *_rows('throughput', 'throughput', (
        ('tp.cost', 'decode + dispatch cost [µs/frame]', _get('cost', 'us_per_frame'), None, None),
        ('tp.cost_rate', 'decode + dispatch, frames per CPU-second',
         _get('cost', 'frames_per_cpu_s'), None, None),
        ('tp.knee', 'sustained rate with the 1 kHz loop running (knee) [frames/s]',
         _get('knee', 'knee_hz'), None, _knee_windows),
        ('tp.rx20k', '  at 20k/s: receive threads [µs/frame]',
         _get('knee', 'at_20k', 'us_per_frame_receive'), None, _at20k_window),
        ('tp.sched20k', '  at 20k/s: scheduler period error p99 [µs]',
         _get('knee', 'at_20k', 'scheduler', 'error_us', 'p99'), None, _at20k_window),
        ('tp.slope', 'bridge CPU per motor (1 kHz feedback each) [%/motor]',
         _get('sweep', 'slope_pct_per_motor'), None, _sweep_windows),
        ('tp.m4', '  bridge CPU, 4 motors / 1 bus [%]', _sweep(4), None, _sweep_windows),
        ('tp.m9', '  bridge CPU, 9 motors / 2 buses (standard) [%]',
         _sweep(9), None, _sweep_windows),
        ('tp.m16', '  bridge CPU, 16 motors / 2 buses [%]', _sweep(16), None, _sweep_windows),
        ('tp.m32', '  bridge CPU, 32 motors / 4 buses [%]', _sweep(32), None, _sweep_windows),
    )),
    # 5. baseline
    *_rows('baseline', 'baseline', (
        ('bl.thread.p99', 'scheduler thread: period error p99 [µs]',
         _get('scheduler_thread', 'scheduler', 'error_us', 'p99'), None, _ALL),
        ('bl.ste.p99', 'rclpy timer, SingleThreadedExecutor: p99 [µs]',
         _get('rclpy_single_threaded', 'scheduler', 'error_us', 'p99'), None, _STE),
        ('bl.ratio_p99', '  ratio timer / thread, p99', _get('ratio_p99'), None, _STE),
        ('bl.thread.missed', 'scheduler thread: missed deadlines [%]',
         _get('scheduler_thread', 'scheduler', 'missed_pct'), None, _ALL),
        ('bl.ste.missed', 'rclpy timer, SingleThreadedExecutor: missed [%]',
         _get('rclpy_single_threaded', 'scheduler', 'missed_pct'), None, _STE),
        ('bl.thread.tick.p99', 'scheduler thread: tick duration p99 [µs]',
         _get('scheduler_thread', 'scheduler', 'tick_us', 'p99'), None, _ALL),
        ('bl.thread.cpu', 'scheduler thread: CPU [%]',
         _get('scheduler_thread', 'loop_cpu_pct'), None, _ALL),
        ('bl.ste.cpu', 'rclpy timer, SingleThreadedExecutor: CPU [%]',
         _get('rclpy_single_threaded', 'loop_cpu_pct'), None, _STE),
        ('bl.ratio_cpu', '  ratio timer / thread, CPU', _get('ratio_cpu'), None, _STE),
        ('bl.evt.p99', '(ref) rclpy timer, EventsExecutor: p99 [µs]',
         _get('rclpy_events', 'scheduler', 'error_us', 'p99'), None, _EVT),
        ('bl.evt.cpu', '(ref) rclpy timer, EventsExecutor: CPU [%]',
         _get('rclpy_events', 'loop_cpu_pct'), None, _EVT),
    )),
    # 6. the robot in two processes
    *_rows('split', 'split', (
        ('split.p50', 'scheduler period error p50 [µs]',
         _get('load', 'scheduler', 'error_us', 'p50'), None, _LOAD),
        ('split.p99', 'scheduler period error p99 [µs]',
         _get('load', 'scheduler', 'error_us', 'p99'), None, _LOAD),
        ('split.canary.p99', '  same window, bare 1 kHz sleeper process p99 [µs]',
         _get('canary', 'error_us', 'p99'), None, _LOAD),
        ('split.missed', 'scheduler missed deadlines [%]',
         _get('load', 'scheduler', 'missed_pct'), None, _LOAD),
        ('split.tick.p99', 'scheduler tick duration p99 [µs]',
         _get('load', 'scheduler', 'tick_us', 'p99'), None, _LOAD),
        ('split.lat.wheel.p50', '/vel_cmd -> wheel_fl current p50 [ms]',
         _get('latency', 'wheel_fl', 'total_ms', 'p50'), None, _latency_windows),
        ('split.lat.wheel.p99', '/vel_cmd -> wheel_fl current p99 [ms]',
         _get('latency', 'wheel_fl', 'total_ms', 'p99'), None, _latency_windows),
        ('split.lat.yaw.p99', '/gimbal_cmd -> yaw voltage p99 [ms]',
         _get('latency', 'yaw', 'total_ms', 'p99'), None, _latency_windows),
        ('split.cpu.host_bridge', 'CPU host + bridge (without the sim), streaming [%]',
         _get('load', 'groups', 'host_bridge'), None, _LOAD),
        ('split.cpu.projected', '  every loop at its nominal rate (lower bound) [%]',
         _get('load', 'projected', 'host_bridge'), None, _LOAD),
        ('split.cpu.bridge_proc', 'CPU bridge process, streaming [%]',
         _get('load', 'process_pct_by_role', 'bridge'), None, _LOAD),
        ('split.cpu.host_proc', 'CPU host process, streaming [%]',
         _get('load', 'process_pct_by_role', 'host'), None, _LOAD),
        ('split.rate.scheduler', 'scheduler ticks achieved, streaming [Hz]',
         _get('load', 'loops', 'can-scheduler', 'achieved_hz'), None, _LOAD),
    )),
)

ROWS += (
    *_rows('wire', 'wire', (
        ('wire.rate', 'wheel group frames (0x200) per second',
         _get('frames_per_s'), None, None),
        ('wire.gaps', 'gaps between them over 1.5 ms [%]', _get('late_gap_pct'), None, None),
        ('wire.canary.gaps', '  same window, bare 1 kHz sleeper process: gaps over 1.5 ms [%]',
         _get('canary_gap_pct'), None, None),
        ('wire.gap.max', '  longest gap [ms]', _get('max_gap_ms'), None, None),
        ('wire.delay.median', 'command -> first frame of the new mode, median [ms]',
         _get('delay_ms', 'median'), None, None),
        ('wire.dds.median', '  same commands, DDS one-way latency to another process, median [ms]',
         _get('dds_ms', 'median'), None, None),
        ('wire.delay.max', 'command -> first frame of the new mode, worst [ms]',
         _get('delay_ms', 'max'), None, None),
    )),
)

_OPS = {'<': operator.lt, '<=': operator.le, '>': operator.gt, '>=': operator.ge}


def evaluate(rows: tuple[Row, ...], raw: dict[str, list[dict[str, Any]]]) -> list[dict[str, Any]]:
    """Each row's min / median / max over runs, verdict, steal and load."""
    out = []
    for row in rows:
        runs = raw.get(row.source, [])
        values = [row.extract(run) for run in runs]
        stats = spread(values)
        windows = [w for run in runs for w in (row.windows(run) if row.windows else [])]
        steal = spread(w['steal_pct'] for w in windows)
        load = spread(w['load1_start'] for w in windows)
        verdict = '—'
        if row.target is not None:
            if stats is None:
                verdict = 'n/a'
            else:
                op, bound = row.target
                verdict = 'PASS' if _OPS[op](stats[1], bound) else 'MISS'
        out.append(
            {
                'key': row.key,
                'section': row.section,
                'label': row.label,
                'runs': sum(v is not None for v in values),
                'min': stats[0] if stats else None,
                'median': stats[1] if stats else None,
                'max': stats[2] if stats else None,
                'values': values,
                'target': f'{row.target[0]} {_fmt(row.target[1])}' if row.target else '',
                'verdict': verdict,
                'steal_pct_median': steal[1] if steal else None,
                'steal_pct_max': steal[2] if steal else None,
                'load1_median': load[1] if load else None,
            }
        )
    return out


def _fmt(x: float | None) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return 'n/a'
    ax = abs(x)
    if ax >= 10_000:
        return f'{x:,.0f}'
    if ax >= 100:
        return f'{x:.0f}'
    if ax >= 10:
        return f'{x:.1f}'
    return f'{x:.2f}'


def format_table(evaluated: list[dict[str, Any]]) -> str:
    """A fixed-width table (also valid Markdown), grouped by section."""
    header = ('metric', 'min', 'median', 'max', 'target', 'result', 'steal % med (max)', 'load1')
    label_width = max(len(r['label']) for r in evaluated)
    widths = (label_width, 8, 8, 8, 9, 6, 17, 5)
    align = ('<', '>', '>', '>', '>', '<', '>', '>')

    def line(cells: tuple[str, ...]) -> str:
        parts = (f'{c:{a}{w}}' for c, a, w in zip(cells, align, widths, strict=True))
        return '| ' + ' | '.join(parts) + ' |'

    rule = '|' + '|'.join('-' * (w + 2) for w in widths) + '|'
    lines: list[str] = []
    section = None
    for r in evaluated:
        if r['section'] != section:
            section = r['section']
            if lines:
                lines.append('')
            lines += [f'**{SECTIONS[section]}**', '', line(header), rule]
        steal = ''
        if r['steal_pct_median'] is not None:
            steal = f'{r["steal_pct_median"]:.1f} ({r["steal_pct_max"]:.1f})'
        load = f'{r["load1_median"]:.2f}' if r['load1_median'] is not None else ''
        cells = (
            r['label'],
            _fmt(r['min']),
            _fmt(r['median']),
            _fmt(r['max']),
            r['target'],
            r['verdict'],
            steal,
            load,
        )
        lines.append(line(cells))
    return '\n'.join(lines)
