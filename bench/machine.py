"""Machine facts, CPU steal and load, and CPU time per thread of this process.

Steal comes from the ``cpu`` line of /proc/stat (the ``st`` column of top/vmstat): the
share of all CPUs' time the hypervisor gave to someone else while we wanted to run. On
the shared 2-vCPU VM it swings from 0 to 40-70 % within minutes (docs/ROS_FROM_WHEELS.md), so every
timing figure is reported with the steal and the load average of its own window.

Thread CPU time comes from /proc/self/task/<tid>/schedstat (nanoseconds on the CPU),
falling back to utime+stime of .../stat (clock ticks). Python thread names are not the
kernel's thread names on Python 3.11, so threads are named through ``threading``'s
``native_id``; threads Python does not know (DDS, rclpy's C++ side) keep their kernel name.
"""

from __future__ import annotations

import datetime as dt
import importlib.metadata
import os
import platform
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

_CLK_TCK = os.sysconf('SC_CLK_TCK')


def cpu_model() -> str:
    """The CPU model name from /proc/cpuinfo ('unknown' if absent)."""
    try:
        with open('/proc/cpuinfo', encoding='ascii', errors='replace') as f:
            for line in f:
                if line.startswith('model name'):
                    return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or 'unknown'


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return 'n/a'


def machine_facts() -> dict[str, object]:
    """Date, CPU, cores, kernel, interpreter and library versions, hypervisor flag."""
    hypervisor = False
    try:
        with open('/proc/cpuinfo', encoding='ascii', errors='replace') as f:
            hypervisor = any(line.startswith('flags') and ' hypervisor' in line for line in f)
    except OSError:
        pass
    return {
        'date': dt.datetime.now(dt.UTC).isoformat(timespec='seconds'),
        'cpu_model': cpu_model(),
        'cores': os.cpu_count(),
        'virtualised': hypervisor,
        'kernel': platform.release(),
        'python': sys.version.split()[0],
        'rclpy': _version('ros-rclpy'),
        'python-can': _version('python-can'),
        'numpy': _version('numpy'),
        'commit': _commit(),
    }


def _commit() -> str:
    """The checkout's commit (short), with ``+changes`` when the tree differs from it."""
    root = Path(__file__).resolve().parents[1]
    try:
        head = subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=root, text=True,
                              capture_output=True, check=True).stdout.strip()
        dirty = subprocess.run(['git', 'status', '--porcelain', '--untracked-files=no'],
                               cwd=root, text=True, capture_output=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return 'unknown'
    return head + ('+changes' if dirty.strip() else '')


def read_proc_stat() -> list[int]:
    """The aggregate ``cpu`` line of /proc/stat: user nice system idle iowait irq softirq steal."""
    with open('/proc/stat', encoding='ascii') as f:
        fields = f.readline().split()
    return [int(x) for x in fields[1:9]]


@dataclass(frozen=True)
class WindowFacts:
    """What the machine did during one measurement window.

    Attributes:
        elapsed_s: wall time [s].
        steal_pct: CPU steal, % of all CPUs' time (top's ``st``).
        busy_pct: non-idle, non-steal time, % of all CPUs' time (everyone's load).
        load1_start: 1-minute load average at the start.
        load1_end: 1-minute load average at the end.
    """

    elapsed_s: float
    steal_pct: float
    busy_pct: float
    load1_start: float
    load1_end: float

    def as_dict(self) -> dict[str, float]:
        """Plain dict for JSON."""
        return {
            'elapsed_s': round(self.elapsed_s, 3),
            'steal_pct': round(self.steal_pct, 2),
            'busy_pct': round(self.busy_pct, 2),
            'load1_start': round(self.load1_start, 2),
            'load1_end': round(self.load1_end, 2),
        }


class Window:
    """Measures steal, busy share and load average between construction and :meth:`close`."""

    def __init__(self) -> None:
        self._t0 = time.monotonic()
        self._stat0 = read_proc_stat()
        self._load0 = os.getloadavg()[0]

    def close(self) -> WindowFacts:
        """End the window and return its facts."""
        stat1 = read_proc_stat()
        delta = [b - a for a, b in zip(self._stat0, stat1, strict=True)]
        total = sum(delta) or 1
        idle = delta[3] + delta[4]
        steal = delta[7]
        return WindowFacts(
            elapsed_s=time.monotonic() - self._t0,
            steal_pct=100.0 * steal / total,
            busy_pct=100.0 * (total - idle - steal) / total,
            load1_start=self._load0,
            load1_end=os.getloadavg()[0],
        )


def _task_cpu_ns(task_dir: str) -> int | None:
    try:
        with open(f'{task_dir}/schedstat', encoding='ascii') as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        pass
    try:
        with open(f'{task_dir}/stat', encoding='ascii') as f:
            text = f.read()
    except OSError:
        return None
    # the command name may hold spaces or parentheses: split after the last ')'
    fields = text[text.rindex(')') + 2 :].split()
    return (int(fields[11]) + int(fields[12])) * 1_000_000_000 // _CLK_TCK


def _task_comm(task_dir: str) -> str:
    try:
        with open(f'{task_dir}/comm', encoding='utf-8', errors='replace') as f:
            return f.read().strip()
    except OSError:
        return '?'


def thread_cpu_snapshot() -> dict[int, tuple[str, int]]:
    """{tid: (name, CPU time [ns])} for every thread of this process now.

    Python threads carry their ``threading`` name; the others ``native:<kernel name>``.
    """
    names = {t.native_id: t.name for t in threading.enumerate() if t.native_id is not None}
    snapshot: dict[int, tuple[str, int]] = {}
    base = '/proc/self/task'
    for entry in os.listdir(base):
        tid = int(entry)
        task_dir = f'{base}/{entry}'
        cpu = _task_cpu_ns(task_dir)
        if cpu is None:
            continue
        name = names.get(tid) or f'native:{_task_comm(task_dir)}'
        snapshot[tid] = (name, cpu)
    return snapshot


def thread_cpu_percent(
    before: dict[int, tuple[str, int]], after: dict[int, tuple[str, int]], elapsed_s: float
) -> dict[str, float]:
    """CPU per thread name between two snapshots, % of one core (same names summed).

    A thread born in between counts from zero; one that ended in between is lost (short
    lived threads are not part of the measured systems).
    """
    out: dict[str, float] = {}
    for tid, (name, cpu) in after.items():
        start = before.get(tid, (name, 0))[1]
        out[name] = out.get(name, 0.0) + 100.0 * (cpu - start) / 1e9 / elapsed_s
    return out
