"""Measurement 3: CPU per component of the one-process robot (host, bridge, sim).

``bringup`` runs can_bridge, rm_robot and rm_sim in one process, so the split is by
thread (names from :func:`bench.machine.thread_cpu_snapshot`):

* **bridge**: ``can-scheduler`` (the one loop: in the one-process robot it also runs the
  plugins; update, pack, send at 1 kHz), ``canrx-<bus>`` (decode and dispatch of
  feedback), ``can_bridge-publish`` (joint/actuator states, diagnostics),
  ``canlog-<bus>``. On rm_sim the scheduler's ``send`` also runs the simulated motors'
  command decoding (the sim delivers synchronously), which a socketcan send does not.
* **host**: ``rm_robot-loop`` (the plugins' loop when rm_robot runs alone),
  ``rm_robot-publish`` (the plugins' messages) and the serial readers' threads
  ``hipnuc ...`` and ``referee ...`` (they open the ports; the loop reads them).
* **ROS (shared)**: ``MainThread`` (the EventsExecutor: every subscription callback of
  both nodes) and the native threads (DDS, rclpy's C++ side); shared by host and bridge.
* **sim**: ``rm_sim-physics`` (motor physics, feedback frames, the IMU's pty frames).
* **bench**: the benchmark's own threads (``bench-*``), excluded from every group.

"host + bridge" is bridge + host + ROS (shared): what the robot costs without the
simulator.
"""

from __future__ import annotations

GROUPS = ('bridge', 'host', 'ros_shared', 'sim', 'bench')


def classify(thread_name: str) -> str:
    """The component group of one thread name (see the module docstring)."""
    if thread_name.startswith(('can-scheduler', 'canrx-', 'can_bridge-', 'canlog-')):
        return 'bridge'
    if thread_name.startswith(('rm_robot-', 'hipnuc', 'referee')):
        return 'host'
    if thread_name.startswith('rm_sim-'):
        return 'sim'
    if thread_name.startswith('bench-'):
        return 'bench'
    return 'ros_shared'


def group_percent(per_thread: dict[str, float]) -> dict[str, float]:
    """CPU % of one core per group, plus ``host_bridge`` (bridge + host + ROS shared)."""
    groups = dict.fromkeys(GROUPS, 0.0)
    for name, pct in per_thread.items():
        groups[classify(name)] += pct
    groups['host_bridge'] = groups['bridge'] + groups['host'] + groups['ros_shared']
    return groups
