"""DDS's own one-way latency, for the commands the robot receives, in a process of its own.

Beside the wire measurement it subscribes to /chassis_cmd as the robot does and notes, for
each message, its arrival (wall clock) minus the stamp the publisher set just before
publishing: what DDS alone takes to bring that message to another process in that window.
The robot's command -> first frame delay is judged after taking this off.

    python -m bench.dds_probe <seconds> <start>    # prints one '@@BENCH {json}' line

``start`` (a ``time.time()`` value) is when the window begins; messages before it are
not counted (the process starts early, as the canary does).
"""

from __future__ import annotations

import statistics
import sys
import time
from typing import Any

from bench.protocol import reply


def run(seconds: float, start: float) -> dict[str, Any]:
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor

    from rm_msgs.msg import ChassisCmd

    context = Context()
    rclpy.init(context=context)
    node = rclpy.create_node('bench_dds_probe', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    end = start + seconds
    delays: list[float] = []

    def on_cmd(msg: Any) -> None:
        now = time.time()
        sent = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        if start <= sent <= end:
            delays.append(now - sent)

    node.create_subscription(ChassisCmd, '/chassis_cmd', on_cmd, 10)
    try:
        while time.time() < end + 0.2:
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown()
        node.destroy_node()
        context.try_shutdown()
    if not delays:
        return {'error': 'no stamped /chassis_cmd in the window'}
    ordered = sorted(delays)
    return {
        'count': len(delays),
        'median': 1e3 * statistics.median(ordered),
        'p99': 1e3 * ordered[min(len(ordered) - 1, int(0.99 * len(ordered)))],
    }


if __name__ == '__main__':
    reply(run(float(sys.argv[1]), float(sys.argv[2])))
