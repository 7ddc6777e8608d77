"""DdsJointIO (rm_robot in a process of its own): joint targets on /actuator_cmd."""

import threading

import pytest
from rclpy.node import Node
from rm_base.joints import JointTarget, Mode
from rm_base.plugin import outbox as outbox_module
from rm_base.plugin.node_io import DdsJointIO
from rm_base.plugin.outbox import Outbox
from support.ros import spin_until, wait_until

from rm_msgs.msg import ActuatorCmd, ActuatorState


def _io_and_bridge(context):
    """rm_robot's joint I/O and a node standing in for the bridge, matched."""
    node = Node('dds_io_test', context=context)
    io = DdsJointIO(node)
    bridge = Node('fake_bridge', context=context)
    got = []
    bridge.create_subscription(ActuatorCmd, '/actuator_cmd', got.append, 10)
    assert wait_until(lambda: io.actuator_cmd.get_subscription_count() == 1, 5.0)
    return node, io, bridge, got


def test_joint_targets_go_out_through_the_outbox_thread_never_from_the_loop(ros_context):
    node, io, bridge, got = _io_and_bridge(ros_context)
    target = JointTarget(Mode.VELOCITY, velocity=1.5)
    publishers = []
    real_publish = outbox_module.publish

    def publish(publisher, msg):
        publishers.append((publisher.topic_name, threading.current_thread().name))
        real_publish(publisher, msg)

    io.outbox = Outbox('dds-io-publish')
    io.outbox.pace()
    io.outbox.start()
    try:
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(outbox_module, 'publish', publish)
            io.send({'wheel': target}, node.get_clock().now())
            assert publishers == []  # queued: the loop's tick goes on
            io.outbox.wake()  # the loop's after-tick callback
            assert wait_until(lambda: publishers, 5.0)
        assert publishers == [('/actuator_cmd', 'dds-io-publish')]
        assert spin_until(bridge, lambda: got)
        assert list(got[0].name) == ['wheel'] and got[0].velocity[0] == 1.5
    finally:
        io.outbox.stop()
    bridge.destroy_node()
    node.destroy_node()


def test_without_an_outbox_joint_targets_are_published_at_once(ros_context):
    node, io, bridge, got = _io_and_bridge(ros_context)
    io.send({'wheel': JointTarget(Mode.EFFORT, effort=0.5)}, node.get_clock().now())
    assert spin_until(bridge, lambda: got)
    assert list(got[0].name) == ['wheel'] and got[0].effort[0] == 0.5
    bridge.destroy_node()
    node.destroy_node()


def test_joint_targets_carry_the_stamp_of_the_states_they_came_from(ros_context):
    node, io, bridge, got = _io_and_bridge(ros_context)
    state = ActuatorState(name=['wheel', 'yaw'], position=[0.0, 0.0], velocity=[0.0, 0.0],
                          effort=[0.0, 0.0], temperature=[0.0, 0.0], online=[True, True],
                          error_code=[0, 0])
    state.header.stamp.sec, state.header.stamp.nanosec = 100, 5
    io.joint_states.handle(state, receive_ns=1)
    run_start = io.joint_states.snapshot()
    state.header.stamp.sec = 101  # newer states, arrived while the plugin ran
    io.joint_states.handle(state, receive_ns=2)
    target = {'wheel': JointTarget(Mode.POSITION, position=3.3)}
    io.send(target, node.get_clock().now(), run_start)
    io.send(target, node.get_clock().now())  # outside a run: the view now
    io.send({'lift': JointTarget(Mode.OFF)}, node.get_clock().now())  # no state: from none
    assert spin_until(bridge, lambda: len(got) == 3)
    assert [(m.states_stamp.sec, m.states_stamp.nanosec) for m in got] == [
        (100, 5), (101, 5), (0, 0)
    ]
    bridge.destroy_node()
    node.destroy_node()
