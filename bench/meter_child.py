"""One checkout's side of the lockstep CPU meter (bench/meter.py starts it).

    <checkout>/scripts/with_env.sh python bench/meter_child.py --checkout <checkout> \
        --ticks 2000 --rounds 5

Runs the standard robot of ``<checkout>`` in lockstep (its own test/support/lockstep.py),
streaming the bench's commands at 100 Hz, and times on this thread's CPU clock
(``time.thread_time_ns``: what the thread ran, not what the machine gave others):

- every component of the loop, by wrapping the scheduler's stages (any commit's layout);
- the whole loop tick (``hardware.tick``) and the simulator's step apart;
- each topic's messages handed to the plugins' callbacks (commands, /imu), which the
  harness hands over between ticks where a running robot's loop takes them in a stage;
- a fixed reference workload before each round, so every cost reads in units of it and
  two runs (two commits, two hours) compare on a noisy machine.

Prints one JSON object on its last line. Standard library and the checkout's code only:
this file runs against old commits too.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import struct
import sys
import time
from pathlib import Path
from typing import Any

_THREAD_NS = time.thread_time_ns


def reference_work() -> float:
    """A fixed piece of the work a tick does: floats, struct packing, attribute calls."""
    acc = 0.0
    buf = bytearray(8)
    values = [0.0] * 4
    for i in range(2000):
        v = math.sin(i * 0.001) * 16384.0
        struct.pack_into('>hhhh', buf, 0, int(v), int(-v), i & 0x7FFF, 0)
        a, b, c, _ = struct.unpack_from('>hhhh', buf)
        values[i & 3] = min(max((a - b) * 0.5 + c, -3e4), 3e4)
        acc += values[i & 3] * 1e-3
    return acc


def time_reference(repeats: int) -> int:
    """The reference workload's thread CPU [ns], the lowest of a few runs."""
    best = None
    for _ in range(repeats):
        t0 = _THREAD_NS()
        reference_work()
        spent = _THREAD_NS() - t0
        best = spent if best is None else min(best, spent)
    assert best is not None
    return best


class Timed:
    """A stage of the loop, timed on the thread's CPU clock; the loop sees the stage."""

    def __init__(self, stage: Any, ledger: dict[str, list[int]]) -> None:
        self._stage = stage
        self.name = stage.name
        # the scheduler's ordering reads these; forward whatever the stage declares
        for attr in ('reads', 'writes'):
            if hasattr(stage, attr):
                setattr(self, attr, getattr(stage, attr))
        self._entry = ledger.setdefault(self.name, [0, 0, 0])

    def __call__(self, now_ns: int, dt: float) -> Any:
        t0 = _THREAD_NS()
        worked = self._stage(now_ns, dt)
        entry = self._entry
        entry[0] += _THREAD_NS() - t0
        entry[1] += 1
        if worked is not False:
            entry[2] += 1
        return worked


def wrap_stages(scheduler: Any, ledger: dict[str, list[int]]) -> str:
    """Put Timed around every stage of the scheduler; returns the layout found."""
    if hasattr(scheduler, '_order'):  # one ordered list of components (the loop's own too)
        scheduler._order = tuple(Timed(s, ledger) for s in scheduler._order)
        return 'ordered'
    # the older loop: input and output stages around its own update, pack and send
    scheduler._inputs = tuple(Timed(s, ledger) for s in scheduler._inputs)
    scheduler._outputs = tuple(Timed(s, ledger) for s in scheduler._outputs)
    return 'inputs/outputs'


class _Noop:
    name = 'noop'

    def __call__(self, now_ns: int, dt: float) -> None:
        return None


def wrapper_cost_ns(calls: int = 20_000) -> float:
    """What one Timed call adds to the thread's CPU beside the stage itself [ns]."""
    bare, timed = _Noop(), Timed(_Noop(), {})
    t0 = _THREAD_NS()
    for _ in range(calls):
        bare(0, 0.0)
    t1 = _THREAD_NS()
    for _ in range(calls):
        timed(0, 0.0)
    t2 = _THREAD_NS()
    return max(0.0, ((t2 - t1) - (t1 - t0)) / calls)


def timed_call(fn: Any, ledger: list[int]) -> Any:
    def call(*args: Any, **kwargs: Any) -> Any:
        t0 = _THREAD_NS()
        try:
            return fn(*args, **kwargs)
        finally:
            ledger[0] += _THREAD_NS() - t0
            ledger[1] += 1

    return call


def timed_inject(inject: Any, ledger: dict[str, list[int]]) -> Any:
    """The host's inject, timed per topic: the callbacks a message runs in the plugins."""

    def call(topic: str, msg: Any) -> Any:
        t0 = _THREAD_NS()
        try:
            return inject(topic, msg)
        finally:
            entry = ledger.setdefault(topic, [0, 0])
            entry[0] += _THREAD_NS() - t0
            entry[1] += 1

    return call


def stream_commands(robot: Any) -> None:
    """The bench's load pattern: GYRO at 1 m/s, the gimbal turning, the shooter ready."""
    from geometry_msgs.msg import Twist, Vector3

    from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

    def gimbal() -> Any:
        t = robot.t
        return GimbalCmd(
            mode=GimbalCmd.RATE, rate_yaw=0.5 * math.sin(t), rate_pitch=0.2 * math.sin(0.7 * t)
        )

    robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.GYRO), rate_hz=100)
    robot.publish('/vel_cmd', lambda: Twist(linear=Vector3(x=1.0, y=0.3 * math.sin(0.5 * robot.t))),
                  rate_hz=100)
    robot.publish('/gimbal_cmd', gimbal, rate_hz=100)
    robot.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.READY, speed=15.0), rate_hz=100)


def _counters(stages: dict[str, list[int]], injected: dict[str, list[int]], loop: list[int],
              world: list[int], states: list[int]) -> dict[str, tuple[int, int]]:
    """Every ledger's (CPU [ns], calls) now, by row name."""
    rows = {name: (v[0], v[1]) for name, v in stages.items()}
    rows.update({f'message callbacks {topic}': (v[0], v[1]) for topic, v in injected.items()})
    rows['loop_tick_ns'] = (loop[0], loop[1])
    rows['world_step_ns'] = (world[0], world[1])
    rows['publish_states_ns'] = (states[0], states[1])
    return rows


def measure(checkout: Path, ticks: int, rounds: int, warmup: int) -> dict[str, Any]:
    sys.path.insert(0, str(checkout / 'test'))
    from support.lockstep import LockstepRobot

    stages: dict[str, list[int]] = {}
    loop = [0, 0]
    world = [0, 0]
    states = [0, 0]
    injected: dict[str, list[int]] = {}
    references: list[int] = []
    with LockstepRobot() as robot:
        stream_commands(robot)
        robot.step(warmup)  # modes settled, caches warm
        hw = robot.bridge.hardware
        layout = wrap_stages(hw.scheduler, stages)
        hw.tick = timed_call(hw.tick, loop)
        robot.world.step = timed_call(robot.world.step, world)
        robot.host.inject = timed_inject(robot.host.inject, injected)
        publish_states = timed_call(robot.bridge.publish_states, states)
        every = max(1, round(1000.0 / float(robot.bridge_parameters.get('publish_rate', 200.0))))
        step_cpu = 0
        per_round: list[dict[str, Any]] = []
        for _ in range(rounds):
            reference = time_reference(5)
            references.append(reference)
            before = _counters(stages, injected, loop, world, states)
            t0 = _THREAD_NS()
            for i in range(ticks):
                robot.step(1)
                if i % every == 0:
                    # the edge thread's work, at its rate: the loop's records to messages
                    publish_states()
            step_cpu += _THREAD_NS() - t0
            after = _counters(stages, injected, loop, world, states)
            # each round against the reference timed just before it: the machine's mood
            # of the moment cancels out round by round
            per_round.append({
                'reference_ns': reference, 'ticks': ticks,
                'rows_ns': {k: after[k][0] - before.get(k, (0, 0))[0] for k in after},
                'stage_calls': sum(after[k][1] - before.get(k, (0, 0))[1]
                                   for k in after if k in stages),
            })
        # read before closing: shutting down runs a last tick of zero output
        return {
            'checkout': str(checkout),
            'layout': layout,
            'ticks': ticks * rounds,
            'reference_ns': sorted(references)[len(references) // 2],
            'references_ns': references,
            'rounds': per_round,
            # the meter's own clock reads around each stage, inside the loop tick
            'wrapper_ns': wrapper_cost_ns(),
            'harness_step_ns': step_cpu,  # all the harness ran, sim and injection included
            'loop_tick_ns': loop[0],
            'world_step_ns': world[0],
            'publish_states_ns': states[0],
            'publish_states_calls': states[1],
            'stages': {
                name: {'ns': v[0], 'calls': v[1], 'worked': v[2]} for name, v in stages.items()
            },
            # messages handed to the plugins' callbacks (commands, /imu, /diagnostics): in
            # a running robot the loop's commands and IMU stages do this work
            'injected': {topic: {'ns': v[0], 'calls': v[1]} for topic, v in injected.items()},
        }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--checkout', type=Path, required=True)
    parser.add_argument('--ticks', type=int, default=2000, help='ticks per round')
    parser.add_argument('--rounds', type=int, default=5)
    parser.add_argument('--warmup', type=int, default=1000, help='ticks before measuring')
    args = parser.parse_args()
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    result = measure(args.checkout.resolve(), args.ticks, args.rounds, args.warmup)
    print(json.dumps(result))
    return 0


if __name__ == '__main__':
    sys.exit(main())
