"""Measurement 5: the obvious alternative, the 1 kHz loop on an rclpy timer.

Same actuators (the standard robot's hardware), same work per tick (``Scheduler.tick``:
update all, pack all, send), same feedback (1 kHz per motor from the feeder of
:mod:`bench.rigs`), back to back in one run:

* **scheduler thread**: ``CanHardware.start()``, the production design (a thread
  sleeping to absolute deadlines on ``perf_counter_ns``);
* **rclpy timer, SingleThreadedExecutor**: ``CanHardware.open()`` (receive threads only)
  and a 1 ms timer on the steady clock whose callback runs ``CanHardware.tick()``, spun by
  ``SingleThreadedExecutor.spin_once`` on a thread of its own;
* **rclpy timer, EventsExecutor**: the same on ``rclpy.experimental.EventsExecutor``
  (for reference: the executor bringup uses for its callbacks).

Period error of the timer: ``start - deadline`` on rcl's own grid (taken from
``time_until_next_call()`` at the first call), followed call by call with rcl's own
bookkeeping (``rcl_timer_call``: the next call one period on, whole periods already past
skipped and counted as missed). The scheduler skips when a tick *ends* past the next
deadline, rcl when a call *starts* past it; each is measured by its own rule. CPU: what
the loop costs its process (:func:`loop_cpu_percent`): the loop thread (scheduler thread,
or the executor thread) with every other thread the loop brings (rclpy's native timer
thread for the EventsExecutor, DDS's threads), as the robot's own CPU counts them.
"""

from __future__ import annotations

import array
import os
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any

from bench.machine import Window, thread_cpu_percent, thread_cpu_snapshot
from bench.rigs import FeedbackFeeder, Rig, standard_hardware
from bench.scheduler_timing import TickRecorder, tick_summary

VARIANTS = ('scheduler_thread', 'rclpy_single_threaded', 'rclpy_events')


@dataclass(frozen=True)
class BaselinePlan:
    """Durations [s] of one baseline run."""

    seconds: float = 5.0
    warmup_s: float = 0.5


QUICK_PLAN = BaselinePlan(seconds=0.3, warmup_s=0.1)


def loop_cpu_percent(per_thread: dict[str, float], loop_thread: str) -> float:
    """CPU [% of a core] of one variant: every thread but the bench's own.

    The bench's own are its main thread (it only waits) and its ``bench-*`` threads (the
    feeder stands in for the wire), except the loop thread itself when the bench starts
    it (the executor's). Native threads count: the EventsExecutor runs its timers on one.
    """
    return sum(
        pct for name, pct in per_thread.items()
        if name == loop_thread or not (name == 'MainThread' or name.startswith('bench-'))
    )


def _measure_scheduler(rig: Rig, plan: BaselinePlan) -> dict[str, Any]:
    rig.hw.start()
    rig.feeder.start()
    time.sleep(plan.warmup_s)
    recorder = TickRecorder(rig.hw.scheduler)
    window = Window()
    threads0 = thread_cpu_snapshot()
    recorder.start()
    time.sleep(plan.seconds)
    sched = recorder.stop()
    threads1 = thread_cpu_snapshot()
    facts = window.close()
    per_thread = thread_cpu_percent(threads0, threads1, facts.elapsed_s)
    return {
        'scheduler': sched,
        'loop_cpu_pct': loop_cpu_percent(per_thread, 'can-scheduler'),
        'window': facts.as_dict(),
    }


def _measure_timer(rig: Rig, plan: BaselinePlan, events: bool) -> dict[str, Any]:
    import rclpy
    from rclpy.clock import Clock, ClockType
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.experimental import EventsExecutor

    rig.hw.open()
    rig.feeder.start()
    context = Context()
    rclpy.init(context=context, domain_id=int(os.environ['ROS_DOMAIN_ID']))
    node = rclpy.create_node('bench_timer_loop', context=context)
    executor = (EventsExecutor if events else SingleThreadedExecutor)(context=context)
    executor.add_node(node)
    period_ns = rig.hw.scheduler.period_ns
    errors = array.array('q')
    recording = threading.Event()
    counts = {'ticks': 0, 'skipped': 0}
    deadline: list[int | None] = [None]
    tick = rig.hw.tick
    clock = time.perf_counter_ns
    timer = None

    def on_timer() -> None:
        start = clock()
        if deadline[0] is None:
            # rcl has moved its next call time one period on: this call's deadline is
            # one period before it (steady time and perf_counter are both CLOCK_MONOTONIC)
            deadline[0] = start + timer.time_until_next_call() - period_ns
        due = deadline[0]
        record = recording.is_set()
        if record:
            errors.append(start - due)
            counts['ticks'] += 1
        # rcl_timer_call's bookkeeping (done as the callback starts): the next call one
        # period on, skipping whole periods already past
        due += period_ns
        if start > due:
            missed = 1 + (start - due - 1) // period_ns
            due += missed * period_ns
            if record:
                counts['skipped'] += missed
        deadline[0] = due
        tick()

    timer = node.create_timer(
        period_ns / 1e9, on_timer, clock=Clock(clock_type=ClockType.STEADY_TIME)
    )
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set() and context.ok():
            executor.spin_once(timeout_sec=0.05)

    thread = threading.Thread(target=spin, name='bench-executor', daemon=True)
    thread.start()
    try:
        time.sleep(plan.warmup_s)
        window = Window()
        threads0 = thread_cpu_snapshot()
        recording.set()
        time.sleep(plan.seconds)
        recording.clear()
        threads1 = thread_cpu_snapshot()
        facts = window.close()
    finally:
        stop.set()
        thread.join(timeout=5.0)
        executor.shutdown()
        node.destroy_node()
        context.try_shutdown()
    per_thread = thread_cpu_percent(threads0, threads1, facts.elapsed_s)
    return {
        'scheduler': tick_summary(errors, ticks=counts['ticks'], skipped=counts['skipped']),
        'loop_cpu_pct': loop_cpu_percent(per_thread, 'bench-executor'),
        'window': facts.as_dict(),
    }


def run_once(plan: BaselinePlan) -> dict[str, Any]:
    """The three variants back to back, each on a fresh rig."""
    sys.setswitchinterval(0.001)  # as in bringup
    out: dict[str, Any] = {}
    for variant in VARIANTS:
        rig = Rig(standard_hardware())
        rig.feeder = FeedbackFeeder(rig, 9000.0)  # 9 motors x 1 kHz, started once open
        try:
            if variant == 'scheduler_thread':
                out[variant] = _measure_scheduler(rig, plan)
            else:
                out[variant] = _measure_timer(rig, plan, events=variant == 'rclpy_events')
        finally:
            rig.feeder.stop()
            rig.close()
    a, b = out['scheduler_thread'], out['rclpy_single_threaded']
    p99_a, p99_b = a['scheduler']['error_us']['p99'], b['scheduler']['error_us']['p99']
    out['ratio_p99'] = p99_b / p99_a if p99_a > 0 else float('nan')
    cpu_a, cpu_b = a['loop_cpu_pct'], b['loop_cpu_pct']
    out['ratio_cpu'] = cpu_b / cpu_a if cpu_a > 0 else float('nan')
    return out
