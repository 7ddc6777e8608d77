"""Measurements 1-3 on the whole standard robot: phases of one robot process.

One run = a fresh robot process (:mod:`bench.robot_proc`: bridge + host + rm_sim, as
``bringup --robot standard --sim``) and a fresh commander process
(:mod:`bench.commander`), then:

1. ``idle``: no commands (plugins PASSIVE, joints held at zero, the 1 kHz loop and the
   simulator still run): CPU and scheduler timing;
2. ``load``: the commander streams /chassis_cmd GYRO, /vel_cmd, /gimbal_cmd RATE and
   /shoot_cmd READY at 100 Hz; once the wheels, the yaw and the friction wheels are
   driven: CPU and scheduler timing, with :mod:`bench.canary` measuring the machine's
   own wake-up latency in the same window;
3. ``latency``: command steps (see :mod:`bench.latency`) with the tap on.

:func:`run_split` repeats the phases with can_bridge (+ rm_sim) and rm_robot in two
processes, the layout of ``ros2 run`` / a launch file.
"""

from __future__ import annotations

import json
import os
import queue
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench.latency import PROBES, analyse
from bench.protocol import PREFIX

ROOT = Path(__file__).resolve().parents[1]
ACTIVE_JOINTS = ('wheel_fl', 'yaw', 'friction_l')
#: How long before a window its bare sleeper is launched (its start-up stays out) [s].
CANARY_LEAD_S = 1.0


class BenchError(RuntimeError):
    """A child process failed or did not answer."""


class Child:
    """A child process speaking the one-line protocol of robot_proc / commander."""

    def __init__(self, module: str, args: list[str], log_path: Path) -> None:
        env = dict(os.environ)
        env['PYTHONPATH'] = os.pathsep.join(p for p in (str(ROOT), env.get('PYTHONPATH')) if p)
        env['PYTHONUNBUFFERED'] = '1'
        self.name = module
        self._log = open(log_path, 'a', encoding='utf-8')
        self.proc = subprocess.Popen(
            [sys.executable, '-m', module, *args],
            cwd=ROOT,
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._log,
            text=True,
            bufsize=1,
        )
        self._replies: queue.Queue[dict[str, Any] | None] = queue.Queue()
        self._reader = threading.Thread(target=self._read, name=f'bench-read-{module}', daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if line.startswith(PREFIX):
                self._replies.put(json.loads(line[len(PREFIX) :]))
            else:
                self._log.write(line)
        self._replies.put(None)

    def wait(self, timeout: float) -> dict[str, Any]:
        try:
            msg = self._replies.get(timeout=timeout)
        except queue.Empty:
            raise BenchError(f'{self.name}: no answer within {timeout:.0f} s') from None
        if msg is None:
            raise BenchError(f'{self.name} exited (code {self.proc.poll()}); see its log')
        if 'error' in msg:
            raise BenchError(f'{self.name}: {msg["error"]}')
        return msg

    def send(self, line: str) -> None:
        assert self.proc.stdin is not None
        try:
            self.proc.stdin.write(line + '\n')
            self.proc.stdin.flush()
        except (BrokenPipeError, OSError) as err:
            raise BenchError(f'{self.name} is gone: {err}') from err

    def request(self, line: str, timeout: float) -> dict[str, Any]:
        self.send(line)
        return self.wait(timeout)

    def close(self, timeout: float = 20.0) -> None:
        if self.proc.poll() is None:
            try:
                assert self.proc.stdin is not None
                self.proc.stdin.write('quit\n')
                self.proc.stdin.close()
            except (BrokenPipeError, OSError):
                pass
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.terminate()
                try:
                    self.proc.wait(5.0)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait()
        self._reader.join(timeout=5.0)
        self._log.close()


@dataclass(frozen=True)
class RobotPlan:
    """Durations of one robot run [s] and the latency pattern."""

    idle_s: float = 5.0
    load_s: float = 10.0
    # enough for a p99 that is not the worst step (of 100: the second-worst)
    steps: int = 100
    hold_s: float = 0.15
    rest_s: float = 0.3
    command_rate_hz: float = 100.0
    settle_s: float = 1.0
    plugins: str = ''
    switch_interval_us: float | None = None


# rest long enough for the wheels to stop between steps on a loaded machine: a step from
# a wheel still turning is left out (unsettled), and a quick run must keep one
QUICK_PLAN = RobotPlan(idle_s=0.3, load_s=0.5, steps=4, hold_s=0.15, rest_s=0.6, settle_s=0.3)


def _domain_conflict(measure: dict[str, Any]) -> list[str]:
    expected = {
        '/chassis_cmd': {'bench_commander'},
        '/gimbal_cmd': {'bench_commander'},
        '/actuator_cmd': {'rm_robot'},
    }
    notes = []
    for topic, nodes in measure.get('publishers', {}).items():
        foreign = set(nodes) - expected.get(topic, set())
        if foreign:
            notes.append(f'foreign publisher(s) {sorted(foreign)} on {topic}: ROS domain shared')
    return notes


def _robot_args(plan: RobotPlan) -> list[str]:
    args = ['--plugins', plan.plugins] if plan.plugins else []
    if plan.switch_interval_us:
        args += ['--switch-interval-us', str(plan.switch_interval_us)]
    return args


def _measure_phases(
    plan: RobotPlan,
    result: dict[str, Any],
    commander: Child,
    bridge: Child,
    measure: Callable[[str, float], dict[str, Any]],
    canary_log: Path,
) -> None:
    """The idle, load (with the canary) and latency phases into result.

    bridge: the process with can_bridge (its joints, its frame tap); measure(phase,
    seconds): one phase's result over every robot process.
    """
    result['idle'] = measure('idle', plan.idle_s)
    commander.request(f'stream {plan.command_rate_hz}', 30.0)
    active = bridge.request('wait_active 20 ' + ' '.join(ACTIVE_JOINTS), 30.0)
    if not active['active']:
        result['notes'].append(f'not every joint driven under load: {active["holds"]}')
    start = time.time() + CANARY_LEAD_S
    canary = Child('bench.canary', [str(plan.load_s), repr(start)], canary_log)
    try:
        time.sleep(max(0.0, start - time.time()))
        result['load'] = measure('load', plan.load_s)
        result['canary'] = canary.wait(30.0)
    finally:
        canary.close()
    commander.request('stop', 10.0)

    tap = bridge.request('tap_on ' + ' '.join(PROBES), 10.0)
    duration = plan.steps * (plan.hold_s + plan.rest_s + 0.01) + plan.settle_s
    steps = commander.request(
        f'steps {plan.steps} {plan.hold_s} {plan.rest_s} {plan.command_rate_hz} {plan.settle_s}',
        duration + 60.0,
    )
    frames = bridge.request('tap_off', 30.0)
    result['latency'] = analyse({**tap, **steps, **frames}, int(plan.hold_s * 1e9))
    for phase in ('idle', 'load'):
        result['notes'] += _domain_conflict(result[phase])


def run_once(plan: RobotPlan, log_dir: Path, tag: str) -> dict[str, Any]:
    """One robot run (see the module docstring); returns the raw phase results."""
    result: dict[str, Any] = {'notes': []}
    robot = Child('bench.robot_proc', _robot_args(plan), log_dir / f'robot_{tag}.log')
    commander = Child('bench.commander', [], log_dir / f'commander_{tag}.log')
    try:
        t0 = time.monotonic()
        result['switch_interval_s'] = robot.wait(90.0)['switch_interval_s']
        ready = robot.request('ready 30', 40.0)
        result['startup_s'] = round(time.monotonic() - t0, 2)
        offline = [j for j, ok in ready['online'].items() if not ok]
        if offline:
            result['notes'].append(f'joints without feedback at start: {offline}')
        result['plugins'] = ready['plugins']
        commander.wait(60.0)

        _measure_phases(
            plan,
            result,
            commander,
            robot,
            lambda phase, seconds: robot.request(f'measure {phase} {seconds}', seconds + 30.0),
            log_dir / f'canary_{tag}.log',
        )
    finally:
        commander.close()
        robot.close()
    return result


def _profile_streaming(
    plan: RobotPlan, robots: dict[str, Child], commander: Child, log_dir: Path, seconds: float
) -> dict[str, Any]:
    """Stream the load pattern, then profile every robot process in the same window.

    robots: role -> process, can_bridge's first; role '' for the one-process robot.
    """
    for child in robots.values():
        child.wait(90.0)
        child.request('ready 30', 40.0)
    commander.wait(60.0)
    commander.request(f'stream {plan.command_rate_hz}', 30.0)
    next(iter(robots.values())).request('wait_active 20 ' + ' '.join(ACTIVE_JOINTS), 30.0)
    time.sleep(1.0)
    for role, child in robots.items():
        (log_dir / role).mkdir(exist_ok=True)
        child.send(f'profile {seconds} {log_dir / role}')
    out: dict[str, Any] = {}
    for role, child in robots.items():
        profiles = child.wait(seconds + 60.0)['profiles']
        out.update({f'{role}/{name}' if role else name: data for name, data in profiles.items()})
    return out


def profile(plan: RobotPlan, log_dir: Path, seconds: float) -> dict[str, Any]:
    """Profile every robot thread for ``seconds`` while the load pattern streams."""
    robot = Child('bench.robot_proc', _robot_args(plan), log_dir / 'robot_profile.log')
    commander = Child('bench.commander', [], log_dir / 'commander_profile.log')
    try:
        return _profile_streaming(plan, {'': robot}, commander, log_dir, seconds)
    finally:
        commander.close()
        robot.close()


def profile_split(plan: RobotPlan, log_dir: Path, seconds: float) -> dict[str, Any]:
    """Profile both processes of the split robot (as ``run_split`` lays it out)."""
    imu_dir = tempfile.mkdtemp(prefix='rm_bench_imu_')
    common = ['--imu-dir', imu_dir, *_robot_args(plan)]
    robots = {
        role: Child(
            'bench.robot_proc', ['--role', role, *common], log_dir / f'split_{role}_profile.log'
        )
        for role in ('bridge', 'host')
    }
    commander = Child('bench.commander', [], log_dir / 'split_commander_profile.log')
    try:
        return _profile_streaming(plan, robots, commander, log_dir, seconds)
    finally:
        for child in (commander, robots['host'], robots['bridge']):
            child.close()
        shutil.rmtree(imu_dir, ignore_errors=True)


def _merge(bridge: dict[str, Any], host: dict[str, Any]) -> dict[str, Any]:
    """One phase of the split robot as one result: groups summed over both processes."""
    merged = dict(bridge)
    merged['groups'] = {k: bridge['groups'][k] + host['groups'][k] for k in bridge['groups']}
    merged['projected'] = {
        k: bridge['projected'][k] + host['projected'][k] for k in bridge['projected']
    }
    merged['loops'] = {**bridge['loops'], **host['loops']}
    merged['threads'] = {
        **{f'bridge/{k}': v for k, v in bridge['threads'].items()},
        **{f'host/{k}': v for k, v in host['threads'].items()},
    }
    merged['process_pct'] = bridge['process_pct'] + host['process_pct']
    merged['process_pct_by_role'] = {
        'bridge': bridge['process_pct'],
        'host': host['process_pct'],
    }
    merged['plugin_overruns'] = host['plugin_overruns']
    merged['publishers'] = {
        t: sorted(set(bridge['publishers'][t]) | set(host['publishers'][t]))
        for t in bridge['publishers']
    }
    return merged


def _measure_both(
    bridge: Child, host: Child, phase: str, seconds: float
) -> tuple[dict[str, Any], dict[str, Any]]:
    bridge.send(f'measure {phase} {seconds}')
    host.send(f'measure {phase} {seconds}')
    return bridge.wait(seconds + 30.0), host.wait(seconds + 30.0)


def run_split(plan: RobotPlan, log_dir: Path, tag: str) -> dict[str, Any]:
    """The same phases with can_bridge (+ rm_sim) and rm_robot in two processes.

    The layout ``ros2 run rm_base can_bridge`` + ``ros2 run rm_base rm_robot`` gives on a
    robot; the simulator lives in the bridge's process (rm_sim is an in-process bus).
    """
    result: dict[str, Any] = {'notes': []}
    imu_dir = tempfile.mkdtemp(prefix='rm_bench_imu_')
    common = ['--imu-dir', imu_dir, *_robot_args(plan)]
    bridge = Child(
        'bench.robot_proc', ['--role', 'bridge', *common], log_dir / f'split_bridge_{tag}.log'
    )
    # all three start at once: the IMU plugin opens the simulator's pty when it appears
    host = Child('bench.robot_proc', ['--role', 'host', *common], log_dir / f'split_host_{tag}.log')
    commander = Child('bench.commander', [], log_dir / f'split_commander_{tag}.log')
    try:
        t0 = time.monotonic()
        bridge.wait(90.0)
        ready = bridge.request('ready 30', 40.0)
        host.wait(90.0)
        result['plugins'] = host.request('ready 30', 40.0)['plugins']
        result['startup_s'] = round(time.monotonic() - t0, 2)
        offline = [j for j, ok in ready['online'].items() if not ok]
        if offline:
            result['notes'].append(f'joints without feedback at start: {offline}')
        commander.wait(60.0)

        _measure_phases(
            plan,
            result,
            commander,
            bridge,
            lambda phase, seconds: _merge(*_measure_both(bridge, host, phase, seconds)),
            log_dir / f'split_canary_{tag}.log',
        )
    finally:
        for child in (commander, host, bridge):  # plugins' zero output before the bridge's
            child.close()
        shutil.rmtree(imu_dir, ignore_errors=True)
    return result
