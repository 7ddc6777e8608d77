"""Measurement 4: how many feedback frames per second the bridge decodes and dispatches.

First the cost of one scheduler tick of the standard robot alone on a thread (update,
pack, send; the work the 1 kHz loop has to fit), back to back and each after a 0.9 ms
sleep, as the loop runs them. Then three views, all on the bridge's
own code (``ManagedBus`` receive thread and
``dispatch``, the actuators' ``handle_frame``), on rigs without motor physics
(:mod:`bench.rigs`):

* **cost per frame**: ``dispatch`` of realistic DJI feedback frames in a tight loop on one
  thread (decode, convert to SI, store; no receive queue), CPU time per frame;
* **knee**: the standard robot's hardware runs (1 kHz scheduler, both receive threads)
  while a feeder thread puts feedback frames into the receive queues at a rising rate.
  A rate is *sustained* when the receive threads keep up (dispatched >= 97 % of offered,
  no overflow, the queue not growing); the knee is the highest sustained rate. The
  scheduler's period error p99 during the flood is reported too;
* **CPU per motor**: 4, 9 (the standard robot), 16 and 32 motors on 1, 2, 2 and 4 buses,
  each motor's feedback at 1 kHz (a DJI ESC's rate) and velocity targets refreshed at
  100 Hz; bridge CPU (scheduler + receive threads) and its least-squares slope.

All three share the GIL with whatever else runs in the process: the feeder is in the
same process (as rm_sim's physics thread is in ``bringup``), and its CPU is reported
apart.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from typing import Any

from bench.cpu import classify
from bench.machine import Window, thread_cpu_percent, thread_cpu_snapshot
from bench.rigs import FeedbackFeeder, Rig, standard_hardware, synthetic_hardware
from bench.scheduler_timing import TickRecorder
from bench.stats import linear_fit

#: (motors, buses) of the CPU-per-motor sweep; 9 is the standard robot itself.
MOTOR_SWEEP = ((4, 1), (9, 2), (16, 2), (32, 4))
KNEE_RATES = (5_000, 10_000, 20_000, 30_000, 40_000, 60_000, 80_000)
#: Sleep after each tick of the slept tick cost [s]: about the loop's own between ticks.
TICK_PAUSE_S = 0.0009


@dataclass(frozen=True)
class ThroughputPlan:
    """Sizes and durations [s] of one throughput run."""

    cost_frames: int = 200_000
    tick_count: int = 5_000
    slept_tick_count: int = 2_000
    knee_rates: tuple[int, ...] = KNEE_RATES
    knee_s: float = 1.5
    sweep_s: float = 3.0
    warmup_s: float = 0.3


QUICK_PLAN = ThroughputPlan(
    cost_frames=20_000,
    tick_count=500,
    slept_tick_count=200,
    knee_rates=(5_000, 20_000),
    knee_s=0.2,
    sweep_s=0.25,
    warmup_s=0.1,
)


def dispatch_cost(frames_total: int) -> dict[str, Any]:
    """CPU time per frame of ``ManagedBus.dispatch`` on the standard robot's buses."""
    rig = Rig(standard_hardware())
    try:
        streams = []
        for bus_name, per_joint in rig.feedback_frames().items():
            dispatch = rig.hw.buses[bus_name].dispatch
            streams += [(dispatch, frame) for frames in per_joint for frame in frames]
        n = len(streams)
        now = time.perf_counter_ns()
        for i in range(2000):  # warm up
            dispatch, frame = streams[i % n]
            dispatch(frame, now)
        c0 = time.thread_time_ns()
        for i in range(frames_total):
            dispatch, frame = streams[i % n]
            dispatch(frame, now)
        cost_ns = (time.thread_time_ns() - c0) / frames_total
    finally:
        rig.close()
    return {'us_per_frame': cost_ns / 1e3, 'frames_per_cpu_s': 1e9 / cost_ns}


def tick_cost(ticks: int, pause_s: float = 0.0) -> dict[str, Any]:
    """CPU time of one ``Scheduler.tick`` of the standard robot, alone on one thread.

    Every joint online and commanded (velocity targets, fresh feedback every 10 ticks), the
    frames sent to empty rm_sim channels: the work of a tick without any contention.
    With pause_s, the thread sleeps that long after each tick, as the 1 kHz loop does: on
    a VM the same work can cost more after a sleep (docs/PERFORMANCE.md, "Latest table").
    """
    rig = Rig(standard_hardware())
    try:
        rig.hw.open()
        now = time.perf_counter_ns
        streams = [
            (rig.hw.buses[bus].dispatch, frames[0])
            for bus, per_joint in rig.feedback_frames().items()
            for frames in per_joint
        ]

        def refresh() -> None:
            t = now()
            for dispatch, frame in streams:
                dispatch(frame, t)
            rig.command_all()

        refresh()
        for _ in range(200):  # warm up
            rig.hw.tick()
        spent = 0
        for i in range(ticks):
            if i % 10 == 0:
                refresh()
            c0 = time.thread_time_ns()
            rig.hw.tick()
            spent += time.thread_time_ns() - c0
            if pause_s:
                time.sleep(pause_s)
        holds = {a.hold_reason.value for a in rig.hw.actuators.values()}
    finally:
        rig.close()
    us = spent / ticks / 1e3
    return {'us_per_tick': us, 'pct_at_1khz': us / 10.0, 'holds': sorted(holds)}


def _bridge_threads(per_thread: dict[str, float]) -> dict[str, float]:
    scheduler = sum(v for k, v in per_thread.items() if k == 'can-scheduler')
    receive = sum(v for k, v in per_thread.items() if k.startswith('canrx-'))
    feeder = sum(v for k, v in per_thread.items() if k == 'bench-feeder')
    other = sum(v for k, v in per_thread.items() if classify(k) != 'bridge' and k != 'bench-feeder')
    return {
        'scheduler_pct': scheduler,
        'receive_pct': receive,
        'bridge_pct': scheduler + receive,
        'feeder_pct': feeder,
        'other_pct': other,
    }


def _backlog(rig: Rig) -> int:
    return sum(rig.sim_bus(name)._queue.qsize() for name in rig.hw.buses)


def _overflows(rig: Rig) -> int:
    return sum(rig.sim_bus(name).rx_overflows for name in rig.hw.buses)


def _received(rig: Rig) -> int:
    return sum(bus.stats().frames_received for bus in rig.hw.buses.values())


def flood(rig: Rig, rate_hz: float, seconds: float, warmup_s: float) -> dict[str, Any]:
    """Run the rig (already started) with the feeder at rate_hz; measure one window."""
    feeder = FeedbackFeeder(rig, rate_hz)
    recorder = TickRecorder(rig.hw.scheduler)
    feeder.start()
    try:
        time.sleep(warmup_s)
        sent0, received0, backlog0, over0 = (
            feeder.sent,
            _received(rig),
            _backlog(rig),
            _overflows(rig),
        )
        window = Window()
        threads0 = thread_cpu_snapshot()
        recorder.start()
        time.sleep(seconds)
        sched = recorder.stop()
        threads1 = thread_cpu_snapshot()
        facts = window.close()
        sent1, received1, backlog1, over1 = (
            feeder.sent,
            _received(rig),
            _backlog(rig),
            _overflows(rig),
        )
    finally:
        feeder.stop()
    elapsed = facts.elapsed_s
    offered = (sent1 - sent0) / elapsed
    dispatched = (received1 - received0) / elapsed
    cpu = _bridge_threads(thread_cpu_percent(threads0, threads1, elapsed))
    growth = backlog1 - backlog0
    sustained = (
        offered > 0
        and dispatched >= 0.97 * offered
        and over1 == over0
        and growth <= max(50, 0.02 * offered * elapsed)
    )
    return {
        'target_hz': rate_hz,
        'offered_hz': offered,
        'dispatched_hz': dispatched,
        'backlog_growth': growth,
        'overflows': over1 - over0,
        'sustained': sustained,
        'us_per_frame_receive': (
            1e4 * cpu['receive_pct'] / dispatched if dispatched > 0 else float('nan')
        ),
        'cpu': cpu,
        'scheduler': sched,
        'window': facts.as_dict(),
    }


def knee(plan: ThroughputPlan) -> dict[str, Any]:
    """Rising flood rates on the standard robot's hardware; the highest sustained one."""
    rig = Rig(standard_hardware())
    points = []
    try:
        rig.hw.start()
        failures = 0
        for rate in plan.knee_rates:
            point = flood(rig, rate, plan.knee_s, plan.warmup_s)
            points.append(point)
            failures = 0 if point['sustained'] else failures + 1
            # drain what is left before the next rate
            deadline = time.monotonic() + 2.0
            while _backlog(rig) and time.monotonic() < deadline:
                time.sleep(0.01)
            if failures >= 2:
                break
    finally:
        rig.close()
    sustained = [p['offered_hz'] for p in points if p['sustained']]
    at_20k = next((p for p in points if p['target_hz'] == 20_000), None)
    return {'knee_hz': max(sustained) if sustained else 0.0, 'points': points, 'at_20k': at_20k}


def motor_sweep(plan: ThroughputPlan) -> dict[str, Any]:
    """Bridge CPU with 4..32 motors, each fed at 1 kHz; slope [% of a core per motor]."""
    points = []
    for motors, buses in MOTOR_SWEEP:
        hardware = standard_hardware() if motors == 9 else synthetic_hardware(motors, buses)
        rig = Rig(hardware)
        try:
            rig.hw.start()
            point = flood(rig, 1000.0 * motors, plan.sweep_s, plan.warmup_s)
        finally:
            rig.close()
        point['motors'] = motors
        point['buses'] = buses
        points.append(point)
    xs = [p['motors'] for p in points]
    slope, intercept = linear_fit(xs, [p['cpu']['bridge_pct'] for p in points])
    sched_slope, _ = linear_fit(xs, [p['cpu']['scheduler_pct'] for p in points])
    rx_slope, _ = linear_fit(xs, [p['cpu']['receive_pct'] for p in points])
    return {
        'points': points,
        'slope_pct_per_motor': slope,
        'intercept_pct': intercept,
        'scheduler_slope_pct_per_motor': sched_slope,
        'receive_slope_pct_per_motor': rx_slope,
    }


def run_once(plan: ThroughputPlan) -> dict[str, Any]:
    """One throughput run: cost per frame, knee, CPU per motor."""
    sys.setswitchinterval(0.001)  # as in bringup (RobotHost lowers it process-wide)
    return {
        'tick': tick_cost(plan.tick_count),
        'tick_after_sleep': tick_cost(plan.slept_tick_count, TICK_PAUSE_S),
        'cost': dispatch_cost(plan.cost_frames),
        'knee': knee(plan),
        'sweep': motor_sweep(plan),
    }
