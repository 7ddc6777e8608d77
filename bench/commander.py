"""Child process of the bench: the command source, as a planner or a teleop would be.

Publishes /chassis_cmd, /vel_cmd, /gimbal_cmd and /shoot_cmd from its own process (its
own DDS participant), driven by one command per stdin line, one ``@@BENCH {json}`` reply
per command on stdout:

* ``stream <rate_hz>``: the load pattern until ``stop``: chassis GYRO translating at
  1 m/s, gimbal RATE with slowly varying rates, shooter READY at 15 m/s;
* ``steps <n> <hold_s> <rest_s> <rate_hz> [<settle_s>]``: the latency pattern: chassis
  RAW (shooter READY as before), every topic at rate_hz, settle_s (1 s) at rest, then n
  steps: /vel_cmd vx 0 -> 1.5 m/s and
  /gimbal_cmd rate_yaw 0 -> 8 rad/s, held hold_s, back to 0 for rest_s (+ 0-10 ms of
  random jitter, so steps fall at every phase of the plugins' periods). A step is
  published the moment it is due, not on the rate grid; its time is taken on
  CLOCK_MONOTONIC just before the publish call;
* ``stop``, ``quit``.

Run as ``python -m bench.commander`` from the repository root.
"""

from __future__ import annotations

import math
import random
import sys
import threading
import time
from typing import Any

from bench.protocol import reply, serve

#: The latency steps: chassis RAW with acceleration limits far above the defaults (so the
#: first plugin tick after the step already asks for the full wheel effort) and a power
#: limit that does not scale it down.
STEP_VX = 1.5  # [m/s]
STEP_RATE_YAW = 8.0  # [rad/s]
STEP_ACCEL = (50.0, 50.0, 200.0)  # [m/s^2, m/s^2, rad/s^2]
STEP_POWER_LIMIT = 500.0  # [W]
SETTLE_S = 1.0  # [s] at rest before the first step


class Commander:
    def __init__(self) -> None:
        import os

        import rclpy
        from geometry_msgs.msg import Twist
        from rclpy.context import Context
        from rclpy.qos import QoSProfile

        from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

        self.rclpy = rclpy
        self.context = Context()
        rclpy.init(context=self.context, domain_id=int(os.environ['ROS_DOMAIN_ID']))
        self.node = rclpy.create_node('bench_commander', context=self.context)
        qos = QoSProfile(depth=10)
        self.types = {'chassis': ChassisCmd, 'vel': Twist, 'gimbal': GimbalCmd, 'shoot': ShootCmd}
        self.pubs = {
            'chassis': self.node.create_publisher(ChassisCmd, '/chassis_cmd', qos),
            'vel': self.node.create_publisher(Twist, '/vel_cmd', qos),
            'gimbal': self.node.create_publisher(GimbalCmd, '/gimbal_cmd', qos),
            'shoot': self.node.create_publisher(ShootCmd, '/shoot_cmd', qos),
        }
        self._stream: tuple[threading.Event, threading.Thread] | None = None

    def close(self) -> None:
        self.stop_stream()
        self.node.destroy_node()
        self.context.try_shutdown()

    def wait_subscribers(self, timeout: float) -> dict[str, int]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if all(p.get_subscription_count() > 0 for p in self.pubs.values()):
                break
            time.sleep(0.02)
        return {k: p.get_subscription_count() for k, p in self.pubs.items()}

    # -- messages -------------------------------------------------------------------------
    def _stamp(self, msg: Any) -> Any:
        msg.header.stamp = self.node.get_clock().now().to_msg()
        return msg

    def chassis(self, mode: int, accel: tuple[float, float, float] | None = None) -> Any:
        msg = self.types['chassis']()
        msg.mode = mode
        if accel is not None:
            msg.accel.linear.x, msg.accel.linear.y, msg.accel.angular.z = accel
            msg.power_limit = STEP_POWER_LIMIT
        return self._stamp(msg)

    def vel(self, vx: float, vy: float = 0.0) -> Any:
        msg = self.types['vel']()
        msg.linear.x = vx
        msg.linear.y = vy
        return msg

    def gimbal(self, rate_yaw: float, rate_pitch: float = 0.0) -> Any:
        cls = self.types['gimbal']
        msg = cls()
        msg.mode = cls.RATE
        msg.rate_yaw = rate_yaw
        msg.rate_pitch = rate_pitch
        return self._stamp(msg)

    def shoot(self) -> Any:
        cls = self.types['shoot']
        msg = cls()
        msg.mode = cls.READY
        msg.speed = 15.0
        return self._stamp(msg)

    # -- the load pattern -------------------------------------------------------------------
    def start_stream(self, rate_hz: float) -> dict[str, Any]:
        self.stop_stream()
        subs = self.wait_subscribers(10.0)
        stop = threading.Event()
        gyro = self.types['chassis'].GYRO

        def run() -> None:
            period = 1.0 / rate_hz
            t0 = deadline = time.monotonic()
            while not stop.is_set():
                t = time.monotonic() - t0
                self.pubs['chassis'].publish(self.chassis(gyro))
                self.pubs['vel'].publish(self.vel(1.0, 0.3 * math.sin(0.5 * t)))
                self.pubs['gimbal'].publish(self.gimbal(0.5 * math.sin(t), 0.2 * math.sin(0.7 * t)))
                self.pubs['shoot'].publish(self.shoot())
                deadline += period
                stop.wait(max(0.0, deadline - time.monotonic()))

        thread = threading.Thread(target=run, name='bench-stream', daemon=True)
        self._stream = (stop, thread)
        thread.start()
        return {'streaming': True, 'subscribers': subs}

    def stop_stream(self) -> dict[str, Any]:
        if self._stream is not None:
            self._stream[0].set()
            self._stream[1].join(timeout=2.0)
            self._stream = None
        return {'streaming': False}

    # -- the latency pattern ---------------------------------------------------------------
    def steps(
        self, n: int, hold_s: float, rest_s: float, rate_hz: float, settle_s: float = SETTLE_S
    ) -> dict[str, Any]:
        self.stop_stream()
        subs = self.wait_subscribers(10.0)
        raw = self.types['chassis'].RAW
        period = 1.0 / rate_hz
        rng = random.Random(7)
        now = time.monotonic()
        # settle in RAW at rest first (the load pattern spun the chassis), then the steps
        changes: list[tuple[float, bool]] = []
        t = now + max(rest_s, settle_s)
        for _ in range(n):
            t += rng.uniform(0.0, 0.01)
            changes.append((t, True))
            changes.append((t + hold_s, False))
            t += hold_s + rest_s
        end = t
        up = False
        records: list[dict[str, Any]] = []
        next_tick = now
        i = 0
        while True:
            next_change = changes[i][0] if i < len(changes) else math.inf
            due = min(next_tick, next_change)
            if due > end:
                break
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            step = next_change <= next_tick
            if step:
                up = changes[i][1]
                i += 1
            vx = STEP_VX if up else 0.0
            rate = STEP_RATE_YAW if up else 0.0
            chassis = self.chassis(raw, STEP_ACCEL)
            vel = self.vel(vx)
            gimbal = self.gimbal(rate)
            t_vel = time.monotonic_ns()
            self.pubs['vel'].publish(vel)
            self.pubs['chassis'].publish(chassis)
            t_gimbal = time.monotonic_ns()
            self.pubs['gimbal'].publish(gimbal)
            self.pubs['shoot'].publish(self.shoot())
            if step:
                records.append(
                    {'up': up, 't_vel_ns': t_vel, 't_gimbal_ns': t_gimbal, 'vx': vx, 'rate': rate}
                )
            else:
                next_tick += period
        return {'steps': records, 'subscribers': subs}


def main() -> int:
    try:
        commander = Commander()
    except Exception as err:
        reply({'error': f'commander did not start: {type(err).__name__}: {err}'})
        return 1
    reply({'started': True})
    try:
        serve({
            'stream': lambda a: commander.start_stream(float(a[0])),
            'stop': lambda a: commander.stop_stream(),
            'steps': lambda a: commander.steps(
                int(a[0]), float(a[1]), float(a[2]), float(a[3]), *(float(x) for x in a[4:5])
            ),
        })
    finally:
        commander.close()
    return 0


if __name__ == '__main__':
    sys.exit(main())
