"""Child process for cross-process tests: publish sample messages, then exit.

Usage: python -m support.publish_child <topic> <pkg/msg/Type> <seed>

Publishes support.msg_samples.sample_message(Type, seed) with transient-local durability
every 50 ms until a subscriber has matched and 10 messages went out (or 20 s pass).
"""

import os
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile

from support.msg_samples import message_class, sample_message


def main() -> int:
    topic, type_name, seed = sys.argv[1:4]
    assert os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE') == 'LOCALHOST'
    rclpy.init()
    node = rclpy.create_node('publish_child')
    cls = message_class(type_name)
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    pub = node.create_publisher(cls, topic, qos)
    msg = sample_message(cls, seed)
    deadline = time.monotonic() + 20.0
    sent = 0
    while time.monotonic() < deadline and sent < 10:
        if pub.get_subscription_count() > 0:
            pub.publish(msg)
            sent += 1
        time.sleep(0.05)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0 if sent else 1


if __name__ == '__main__':
    sys.exit(main())
