"""rmcli node, topic info/type, service list/type and interface show against a test node."""

import pathlib

import pytest
import rclpy
from rclpy.qos import qos_profile_sensor_data
from std_msgs.msg import String
from std_srvs.srv import Trigger
from support.ros import run_rmcli, spinning

from rm_msgs.msg import ChassisCmd

pytestmark = pytest.mark.ros

TIMEOUT_S = 30.0
ROOT = pathlib.Path(__file__).resolve().parents[2]


def rmcli(*args):
    return run_rmcli(*args, timeout=TIMEOUT_S)


@pytest.fixture
def graph(ros_context):
    """/robot_like: publishes /chatter, subscribes /chassis_cmd best effort, serves ~/reset."""
    node = rclpy.create_node('robot_like', context=ros_context)
    node.create_publisher(String, 'chatter', 10)
    node.create_subscription(ChassisCmd, 'chassis_cmd', lambda _m: None, qos_profile_sensor_data)
    node.create_service(Trigger, '~/reset', lambda _r, response: response)
    with spinning(node):
        yield node
    node.destroy_node()


def test_node_list_and_info_show_the_node_and_its_endpoints(graph):
    code, out, err = rmcli('node', 'list')
    assert code == 0, err
    assert '/robot_like' in out.splitlines()
    assert not [n for n in out.splitlines() if '/_' in n]  # rmcli's own node is hidden
    code, out, err = rmcli('node', 'info', '/robot_like')
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == '/robot_like'
    subscribers = lines.index('  Subscribers:')
    publishers = lines.index('  Publishers:')
    servers = lines.index('  Service Servers:')
    assert '    /chassis_cmd: rm_msgs/msg/ChassisCmd' in lines[subscribers:publishers]
    assert '    /chatter: std_msgs/msg/String' in lines[publishers:servers]
    assert '    /robot_like/reset: std_srvs/srv/Trigger' in lines[servers:]
    assert rmcli('node', 'info', '/nobody', '--spin-time', '0')[2] == (
        "rmcli: error: Unable to find node '/nobody'\n")


def test_topic_info_counts_endpoints_and_verbose_shows_each_qos(graph):
    code, out, err = rmcli('topic', 'info', '/chassis_cmd')
    assert code == 0, err
    assert out.splitlines() == [
        'Type: rm_msgs/msg/ChassisCmd', 'Publisher count: 0', 'Subscription count: 1',
    ]
    code, out, err = rmcli('topic', 'info', '-v', '/chassis_cmd')
    assert code == 0, err
    assert 'Node name: robot_like' in out and 'Endpoint type: SUBSCRIPTION' in out
    assert 'Reliability: BEST_EFFORT' in out
    assert rmcli('topic', 'type', '/chatter')[1] == 'std_msgs/msg/String\n'


def test_service_list_and_type(graph):
    code, out, err = rmcli('service', 'list', '-t')
    assert code == 0, err
    assert '/robot_like/reset [std_srvs/srv/Trigger]' in out.splitlines()
    assert rmcli('service', 'type', '/robot_like/reset')[1] == 'std_srvs/srv/Trigger\n'


def test_interface_show_prints_the_installed_definition():
    code, out, err = rmcli('interface', 'show', 'rm_msgs/msg/ChassisCmd')
    assert code == 0, err
    # the file as installed, comments and all
    assert out == (ROOT / 'rm_msgs' / 'msg' / 'ChassisCmd.msg').read_text()
    code, out, _ = rmcli('interface', 'show', 'std_srvs/srv/Trigger')
    assert code == 0 and '---' in out
    code, _, err = rmcli('interface', 'show', 'rm_msgs/msg/Nothing')
    assert code == 1 and 'Could not find the interface' in err
