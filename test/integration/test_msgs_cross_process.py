"""Each rm_msgs message, published in one process, arrives field for field in another."""

import sys

import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile
from support.msg_samples import message_class, sample_message
from support.ros import start_process, stop_process, wait_until

pytestmark = pytest.mark.ros

RM_MSGS = [
    'ChassisCmd', 'GimbalCmd', 'ShootCmd', 'ActuatorCmd', 'ActuatorState', 'PluginState',
    'ChassisState', 'GimbalState', 'ShooterState', 'GpioCmd', 'GpioState', 'CanFrame',
]


def test_sample_messages_set_every_field_away_from_its_default():
    # Guard for the round trip below: a field left at its default would pass unseen.
    for name in RM_MSGS:
        cls = message_class(f'rm_msgs/msg/{name}')
        sample, default = sample_message(cls, 'x'), cls()
        for field in cls.get_fields_and_field_types():
            assert getattr(sample, field) != getattr(default, field), f'{name}.{field}'


@pytest.mark.parametrize('name', RM_MSGS)
def test_message_crosses_processes_field_for_field(ros_context, name):
    type_name = f'rm_msgs/msg/{name}'
    topic = f'/test_cross/{name.lower()}'
    cls = message_class(type_name)
    node = rclpy.create_node('cross_process_listener', context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    received = []
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(cls, topic, received.append, qos)
    child = start_process([sys.executable, '-m', 'support.publish_child', topic, type_name, name])
    try:
        # Discovery takes ~0.4 s on a quiet machine; allow far more under CPU steal.
        arrived = wait_until(lambda: received, timeout=30.0, spin=executor.spin_once)
    finally:
        out, err = stop_process(child)
        executor.shutdown()
        node.destroy_node()
    assert arrived, f'nothing received; publisher said:\n{out}\n{err}'

    expected = sample_message(cls, name)
    got = received[0]
    for field in cls.get_fields_and_field_types():
        assert getattr(got, field) == getattr(expected, field), field
    assert got == expected
