"""Measurement 2: command topic -> the first CAN frame that carries the new target.

The commander (:mod:`bench.commander`, its own process) steps /vel_cmd vx 0 -> 1.5 m/s
(chassis RAW, acceleration limits far above the defaults) and /gimbal_cmd rate_yaw
0 -> 8 rad/s, and notes CLOCK_MONOTONIC just before each publish. In the robot process a
second rm_sim bus on can0 stamps every 0x200 / 0x1FF frame on the same clock the moment
the bridge sends it (:mod:`bench.robot_proc`). For each step the latency is the time to
the first frame whose slot (wheel_fl in 0x200, yaw in 0x1FF) leaves the value it held in
the 50 ms before the step by more than a threshold well above that baseline's noise (a
step whose baseline moved by more than half the threshold is left out as *unsettled*):

* wheel_fl: 2000 raw (2.4 A, 0.73 N·m at the wheel; the step asks the effort limit);
* yaw: 1000 raw (0.96 V; the step's rate feed-forward asks ~2.3 V at once).

The same rule on the joint targets the bridge applies (``set_command``: wheel effort,
yaw velocity) splits the path into *publish -> bridge* (DDS to rm_robot, the plugin's
next tick, /actuator_cmd over DDS to can_bridge) and *bridge -> wire* (the next 1 kHz
scheduler tick).
"""

from __future__ import annotations

import statistics
from bisect import bisect_left
from typing import Any

from bench.stats import summary

#: joint -> (commander time key, frame threshold [raw], applied field, applied threshold)
PROBES: dict[str, tuple[str, int, str, float]] = {
    'wheel_fl': ('t_vel_ns', 2000, 'effort', 0.5),
    'yaw': ('t_gimbal_ns', 1000, 'velocity', 2.0),
}
BASELINE_NS = 50_000_000


def _slot_value(data_hex: str, slot: int) -> int:
    data = bytes.fromhex(data_hex)
    return int.from_bytes(data[2 * slot : 2 * slot + 2], 'big', signed=True)


def _first_change(
    times: list[int], values: list[float], t0: int, threshold: float, window_ns: int
) -> tuple[int | None, float]:
    """(time of the first sample after t0 off the pre-t0 baseline, baseline noise)."""
    lo = bisect_left(times, t0 - BASELINE_NS)
    hi = bisect_left(times, t0)
    if hi <= lo:
        return None, float('nan')
    base_values = values[lo:hi]
    base = statistics.median(base_values)
    noise = max(abs(v - base) for v in base_values)
    for i in range(hi, len(times)):
        if times[i] - t0 > window_ns:
            break
        if abs(values[i] - base) > threshold:
            return times[i], noise
    return None, noise


def analyse(result: dict[str, Any], window_ns: int) -> dict[str, Any]:
    """Latency per probe joint from the commander's steps and the robot's tap records.

    Args:
        result: ``{'steps': [...], 'slots': {...}, 'frames': {...}, 'applied': [...]}``.
        window_ns: how long a step is held [ns]; one not seen on the wire by then is
            counted as lost (``steps - unsettled - detected``).

    Returns:
        Per joint: steps, detected, total/to-bridge/to-wire summaries [ms], and the
        largest baseline noise seen (it must stay below the threshold).
    """
    out: dict[str, Any] = {}
    ups = [s for s in result['steps'] if s['up']]
    for joint, (t_key, threshold, field, applied_threshold) in PROBES.items():
        slot = result['slots'].get(joint)
        if slot is None:
            continue
        frames = [
            (t, _slot_value(data, slot['slot']))
            for t, frame_id, data in result['frames'].get(slot['channel'], [])
            if frame_id == slot['id']
        ]
        f_times = [t for t, _ in frames]
        f_values = [v for _, v in frames]
        applied = [
            (t, velocity if field == 'velocity' else effort)
            for t, name, velocity, effort in result['applied']
            if name == joint
        ]
        a_times = [t for t, _ in applied]
        a_values = [v for _, v in applied]
        total, to_bridge, to_wire, noises = [], [], [], []
        unsettled = 0
        for step in ups:
            t0 = step[t_key]
            t_wire, noise = _first_change(f_times, f_values, t0, threshold, window_ns)
            noises.append(noise)
            if noise > threshold / 2:
                # not at rest before the step: a change could be the old motion's
                unsettled += 1
                continue
            if t_wire is None:
                continue
            total.append((t_wire - t0) / 1e6)
            t_app, _ = _first_change(a_times, a_values, t0, applied_threshold, window_ns)
            if t_app is not None and t_app <= t_wire:
                to_bridge.append((t_app - t0) / 1e6)
                to_wire.append((t_wire - t_app) / 1e6)
        finite_noise = [n for n in noises if n == n]
        out[joint] = {
            'steps': len(ups),
            'detected': len(total),
            'unsettled': unsettled,
            'threshold_raw': threshold,
            'baseline_noise_max_raw': max(finite_noise) if finite_noise else None,
            'total_ms': summary(total),
            'to_bridge_ms': summary(to_bridge),
            'to_wire_ms': summary(to_wire),
            'samples_ms': [round(x, 3) for x in total],
        }
    return out
