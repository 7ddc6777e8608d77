"""Child process: flood /actuator_cmd with good and bad messages at a fixed rate.

Usage: python -m reliability.flood_child <rate_hz> <seconds>

Waits until a subscriber matched (at most 20 s), then publishes the mix of
:data:`MIX` round robin at ``rate_hz`` for ``seconds``, paced to absolute deadlines, and
prints ``sent <n> rate <hz>`` on stdout. Exit status 1 if nobody subscribed.
"""

from __future__ import annotations

import math
import os
import sys
import time

import rclpy

from rm_msgs.msg import ActuatorCmd


def command(joint: str, mode: int, **values: float) -> ActuatorCmd:
    """One ActuatorCmd for one joint (unset values are 0)."""
    msg = ActuatorCmd()
    msg.name = [joint]
    msg.mode = [mode]
    for field in ('position', 'velocity', 'effort', 'kp', 'kd'):
        setattr(msg, field, [float(values.get(field, 0.0))])
    return msg


#: Valid, NaN, huge, MIT beyond every range, unknown mode, unknown joint.
MIX = [
    command('wheel', 2, velocity=20.0),
    command('wheel', 2, velocity=math.nan),
    command('yaw', 1, effort=1e9),
    command('arm', 4, position=1e3, kp=1e9, kd=1e9),
    command('wheel', 9, velocity=1.0),
    command('rotor', 1, effort=1.0),
]


def main() -> int:
    """Flood; see the module docstring."""
    rate_hz, seconds = float(sys.argv[1]), float(sys.argv[2])
    assert os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE') == 'LOCALHOST'
    rclpy.init()
    node = rclpy.create_node('flood_child')
    pub = node.create_publisher(ActuatorCmd, 'actuator_cmd', 10)
    deadline = time.monotonic() + 20.0
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    if pub.get_subscription_count() == 0:
        return 1
    sent, start = 0, time.monotonic()
    due = start
    while time.monotonic() < start + seconds:
        pub.publish(MIX[sent % len(MIX)])
        sent += 1
        due += 1.0 / rate_hz
        delay = due - time.monotonic()
        if delay > 0:
            time.sleep(delay)
    print(f'sent {sent} rate {sent / (time.monotonic() - start):.0f}', flush=True)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
