"""``rmcli tune step`` finds the plugin that drives a joint even when discovery is slow.

Discovery shows a host node's state topics one at a time; the owner must be looked for
among all the plugins the host runs (its ``plugins`` parameter), not among the topics seen
first. Here the gimbal's state topic appears a second after the chassis's.
"""

import time

import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rm_base.plugin.base import STATE_QOS
from rm_bringup.cli.errors import CliError
from rm_bringup.cli.tune_step import Owner, _owner
from support.ros import spinning

from rm_msgs.msg import PluginState

pytestmark = pytest.mark.ros

LATE_S = 1.0


def _state(plugin, joints, state_name='PASSIVE'):
    return PluginState(plugin=plugin, enabled=True, state_name=state_name, joints=joints,
                       joint_min=[-1.0] * len(joints), joint_max=[0.5] * len(joints))


@pytest.fixture
def host(ros_context):
    """A host node whose gimbal state shows up LATE_S after its chassis state."""
    node = rclpy.create_node('robot', context=ros_context)
    node.declare_parameter('plugins', ['chassis', 'gimbal'])
    node.create_publisher(PluginState, '/robot/chassis/state', STATE_QOS).publish(
        _state('chassis', ['wheel_fl']))
    late = []

    def gimbal_appears():
        if not late:
            late.append(node.create_publisher(PluginState, '/robot/gimbal/state', STATE_QOS))
            late[0].publish(_state('gimbal', ['yaw', 'pitch']))

    node.create_timer(LATE_S, gimbal_appears)
    with spinning(node):
        yield node
    node.destroy_node()


@pytest.fixture
def cli(ros_context):
    node = rclpy.create_node('tune_cli', context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    yield node, executor
    executor.shutdown()
    node.destroy_node()


def test_the_owner_is_found_among_all_the_hosts_plugins(host, cli):
    node, executor = cli
    owner = _owner(node, executor, 'yaw', time.monotonic() + 30.0)
    assert owner == Owner('/robot', 'gimbal', -1.0, 0.5)


def test_a_plugin_that_never_reports_is_named_not_taken_for_none(ros_context, cli):
    host = rclpy.create_node('mute', context=ros_context)
    host.declare_parameter('plugins', ['chassis', 'gimbal'])
    host.create_publisher(PluginState, '/mute/chassis/state', STATE_QOS).publish(
        _state('chassis', ['wheel_fl']))
    node, executor = cli
    with spinning(host):
        with pytest.raises(CliError, match="no state from /mute/gimbal/state: cannot tell "
                           "who drives 'yaw'"):
            _owner(node, executor, 'yaw', time.monotonic() + 5.0)
    host.destroy_node()
