"""Measurement 7: the wheel group frames as they leave the robot, from a python-can log.

``bringup --robot standard --sim`` runs as a user runs it (rm_sim in its own process), with
can_bridge's ``log_file`` on; this process alternates /chassis_cmd between PASSIVE and RAW
(/vel_cmd 1 m/s forward) every ``period_s``, both streamed at 50 Hz and stamped, and notes
the wall-clock time of each switch. Then can0's log (the bridge stamps each frame with the
wall clock as it sends it) gives:

- the wheel group frame (0x200) rate and the share of gaps between two of them over 1.5 ms;
- per switch, the first 0x200 frame that shows the new mode (PASSIVE: all four currents
  zero; RAW: one not zero) and its delay after the switch was published;
- beside them, the share of gaps over 1.5 ms between the wake-ups of a bare 1 kHz sleeper
  process (:mod:`bench.canary`) over the same switches: what the machine alone gives;
- and DDS's one-way latency of the same /chassis_cmd messages to another process
  (:mod:`bench.dds_probe`): the part of the delay that is not the robot's.
"""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

WHEEL_GROUP_ID = 0x200  # the C620 group frame of wheel ids 1-4 on can0
GAP_S = 0.0015  # [s] a gap over this counts as a late frame
START_TIMEOUT_S = 60.0


@dataclass(frozen=True)
class WirePlan:
    """How long the measurement runs."""

    steps: int = 30
    period_s: float = 0.6
    settle_s: float = 2.0  # [s] after the robot reports, before the first switch


QUICK_PLAN = WirePlan(steps=4, period_s=0.4, settle_s=1.0)


def run_once(plan: WirePlan, log_dir: Path, tag: str) -> dict[str, Any]:
    """Run bringup, alternate the modes, stop it, read can0's log (see the module doc)."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import qos_profile_sensor_data

    from bench.robot import BenchError, Child
    from rm_msgs.msg import ChassisCmd, ChassisState

    workdir = Path(tempfile.mkdtemp(prefix='rm_wire_', dir=log_dir))
    overlay = workdir / 'wire.yaml'
    log_stem = workdir / 'can.log'
    overlay.write_text(f"can_bridge:\n  ros__parameters:\n    log_file: '{log_stem}'\n")
    out = open(workdir / 'bringup.log', 'wb')  # closed below
    proc = subprocess.Popen(
        [sys.executable, '-m', 'rm_bringup.bringup', '--robot', 'standard', '--sim',
         '--no-status', '--params-file', str(overlay)],
        stdout=out, stderr=subprocess.STDOUT, env=dict(os.environ),
    )
    context = Context()
    rclpy.init(context=context)
    node = rclpy.create_node('bench_wire', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    switches: list[tuple[float, int]] = []
    canary = probe = None
    try:
        states: list[Any] = []
        node.create_subscription(ChassisState, '/chassis_state', states.append,
                                 qos_profile_sensor_data)
        cmd_pub = node.create_publisher(ChassisCmd, '/chassis_cmd', 10)
        from geometry_msgs.msg import Twist

        vel_pub = node.create_publisher(Twist, '/vel_cmd', 10)
        deadline = time.monotonic() + START_TIMEOUT_S
        while not states and time.monotonic() < deadline and proc.poll() is None:
            executor.spin_once(timeout_sec=0.05)
        if not states:
            raise RuntimeError('the robot did not report /chassis_state')
        vel = Twist()
        vel.linear.x = 1.0
        mode = ChassisCmd.PASSIVE
        cmd = ChassisCmd(mode=mode)
        next_switch = time.monotonic() + plan.settle_s
        next_publish = time.monotonic()
        # launched now, measuring from the first switch: its start-up stays out of the window
        window = [str(plan.steps * plan.period_s), repr(time.time() + plan.settle_s)]
        canary = Child('bench.canary', window, workdir / 'canary.log')
        probe = Child('bench.dds_probe', window, workdir / 'dds_probe.log')
        while len(switches) < plan.steps or time.monotonic() < next_switch:
            now = time.monotonic()
            if now >= next_switch:
                if len(switches) >= plan.steps:
                    break
                mode = ChassisCmd.RAW if mode == ChassisCmd.PASSIVE else ChassisCmd.PASSIVE
                cmd.mode = mode
                next_switch += plan.period_s
                next_publish = now
                switches.append((time.time(), mode))
            if now >= next_publish:
                cmd.header.stamp = node.get_clock().now().to_msg()
                cmd_pub.publish(cmd)
                vel_pub.publish(vel)
                next_publish += 0.02
            executor.spin_once(timeout_sec=max(0.0, min(next_publish, next_switch) - now))
        sleeper = canary.wait(30.0) if canary is not None else {}
        dds: dict[str, Any] = {}
        if probe is not None:
            try:
                dds = probe.wait(30.0)
            except BenchError as err:  # the delay is still measured; its ratio is n/a
                dds = {'error': str(err)}
    finally:
        for child in (canary, probe):
            if child is not None:
                child.close()
        executor.shutdown()
        node.destroy_node()
        context.try_shutdown()
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        out.close()
    result = analyse(workdir / 'can_can0.log', switches)
    result['canary_gap_pct'] = sleeper.get('late_gap_pct')
    result['dds_ms'] = dds
    if 'error' in dds:
        result.setdefault('notes', []).append(f'DDS latency not measured: {dds["error"]}')
    return result


def analyse(log_path: Path, switches: list[tuple[float, int]]) -> dict[str, Any]:
    """The frame rate, late gaps and mode delays of a log (see the module docstring)."""
    import can

    frames = [
        (msg.timestamp, bytes(msg.data))
        for msg in can.LogReader(str(log_path))
        if msg.arbitration_id == WHEEL_GROUP_ID and not msg.is_rx
    ]
    frames.sort()
    if len(frames) < 2 or not switches:
        return {'frames': len(frames), 'notes': ['no wheel frames or no switch']}
    # Only the stretch of the switches counts (start-up and shut-down aside).
    start, end = switches[0][0], switches[-1][0]
    window = [f for f in frames if start <= f[0] <= end]
    gaps = [b[0] - a[0] for a, b in itertools.pairwise(window)]
    delays = []
    for t, mode in switches:
        passive = mode == 0
        first = next(
            (ft for ft, data in frames if ft >= t and (not any(data) if passive else any(data))),
            None,
        )
        delays.append(None if first is None else first - t)
    seen = [d for d in delays if d is not None]
    return {
        'frames': len(window),
        'frames_per_s': (len(window) - 1) / (window[-1][0] - window[0][0]) if len(window) > 1
        else 0.0,
        'late_gap_pct': 100.0 * sum(g > GAP_S for g in gaps) / len(gaps) if gaps else 0.0,
        'max_gap_ms': 1e3 * max(gaps, default=0.0),
        'delay_ms': {
            'median': 1e3 * sorted(seen)[len(seen) // 2] if seen else None,
            'max': 1e3 * max(seen) if seen else None,
            'missed': len(delays) - len(seen),
            'steps': len(delays),
        },
        'notes': [],
    }
