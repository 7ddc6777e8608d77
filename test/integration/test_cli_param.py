"""rmcli param list/get/set/describe/dump/load in child processes against a test node."""


import pytest
import rclpy
import yaml
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from support.ros import run_rmcli, spinning

pytestmark = pytest.mark.ros

TIMEOUT_S = 30.0  # discovery is ~0.4 s on a quiet machine; far more under CPU steal


def rmcli(*args):
    return run_rmcli(*args, timeout=TIMEOUT_S)


@pytest.fixture
def tuned(ros_context):
    """A node with a tunable gain (kept >= 0 by its callback) and a read-only joint name."""
    node = rclpy.create_node('tuned', context=ros_context)
    node.declare_parameter('loop.kp', 2.0, ParameterDescriptor(
        description='gain [1/s]', additional_constraints='>= 0.0; set while running'))
    node.declare_parameter('loop.limits', [1.0, 2.0])
    node.declare_parameter('joint', 'yaw', ParameterDescriptor(read_only=True))
    # a parameter and a group at once, as can_bridge's `sim` and `sim.timing`
    node.declare_parameter('loop', True, ParameterDescriptor(read_only=True))

    def check(parameters):
        for p in parameters:
            if p.name == 'loop.kp' and p.value < 0.0:
                return SetParametersResult(
                    successful=False, reason=f'loop.kp must be >= 0.0, got {p.value}')
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(check)
    with spinning(node):
        yield node
    node.destroy_node()


def test_list_get_and_describe_print_what_ros2_param_prints(tuned):
    code, out, err = rmcli('param', 'list', '/tuned')
    assert code == 0, err
    assert {'  loop.kp', '  loop.limits', '  joint'} <= set(out.splitlines())
    assert rmcli('param', 'get', '/tuned', 'loop.kp')[1] == 'Double value is: 2.0\n'
    assert rmcli('param', 'get', '/tuned', 'loop.limits')[1] == (
        'Double values are: [1.0, 2.0]\n')
    code, out, _ = rmcli('param', 'describe', '/tuned', 'loop.kp', 'joint')
    assert code == 0
    assert out.splitlines() == [
        'Parameter name: loop.kp', '  Type: double', '  Description: gain [1/s]',
        '  Constraints:', '    Additional constraints: >= 0.0; set while running',
        'Parameter name: joint', '  Type: string', '  Constraints:', '    Read only: true',
    ]


def test_set_goes_through_the_nodes_check_and_a_refusal_is_exit_1_with_its_reason(tuned):
    code, out, err = rmcli('param', 'set', '/tuned', 'loop.kp', '4.5')
    assert (code, out) == (0, 'Set parameter successful\n'), err
    assert tuned.get_parameter('loop.kp').value == 4.5
    code, _, err = rmcli('param', 'set', '/tuned', 'loop.kp', '-1.0')
    assert code == 1
    assert err == 'rmcli: error: Setting parameter failed: loop.kp must be >= 0.0, got -1.0\n'
    code, _, err = rmcli('param', 'set', '/tuned', 'joint', 'pitch')
    assert code == 1 and 'read-only' in err
    assert tuned.get_parameter('joint').value == 'yaw'


def test_set_reads_30_and_1e_3_as_the_numbers_a_double_parameter_wants(tuned):
    # YAML reads 30 as an integer and 1e-3 as a string: ros2 param set sends them so, and a
    # double parameter refuses both as the wrong type
    for text, expected in (('30', 30.0), ('1e-3', 0.001)):
        code, out, err = rmcli('param', 'set', '/tuned', 'loop.kp', text)
        assert (code, out) == (0, 'Set parameter successful\n'), err
        assert tuned.get_parameter('loop.kp').value == expected
    code, _, err = rmcli('param', 'set', '/tuned', 'loop.kp', 'fast')
    assert code == 1 and 'Wrong parameter type' in err, err


def test_set_of_a_name_the_node_lacks_names_the_nearest_ones(tuned):
    code, _, err = rmcli('param', 'set', '/tuned', 'loop.kq', '1.0')
    assert code == 1
    assert err == ('rmcli: error: Setting parameter failed: /tuned has no parameter loop.kq '
                   '(did you mean loop.kp, loop?)\n')


def test_a_dump_loads_back_and_is_a_parameter_file(tuned, tmp_path):
    code, out, err = rmcli('param', 'dump', '/tuned')
    assert code == 0, err
    dumped = yaml.safe_load(out)
    params = dumped['/tuned']['ros__parameters']
    assert params['loop.kp'] == 2.0 and params['loop.limits'] == [1.0, 2.0]
    assert params['joint'] == 'yaw' and params['loop'] is True
    params['loop.kp'] = 3.0
    del params['joint']  # read-only: a load would be refused for it
    path = tmp_path / 'tuned.yaml'
    path.write_text(yaml.safe_dump(dumped))
    code, out, err = rmcli('param', 'load', '/tuned', str(path))
    assert code == 0, out + err
    # only what differs was set: the unchanged limits and read-only values were left alone
    assert out.splitlines() == ['Set parameter loop.kp successful']
    assert tuned.get_parameter('loop.kp').value == 3.0
    params['loop.kp'] = -5.0
    path.write_text(yaml.safe_dump(dumped))
    code, out, _ = rmcli('param', 'load', '/tuned', str(path))
    assert code == 1
    assert out == 'Set parameter loop.kp failed: loop.kp must be >= 0.0, got -5.0\n'


def test_a_config_keyed_by_the_relative_name_loads_as_rcl_reads_it(tuned, tmp_path):
    # rm_bringup/config/ writes 'rm_robot:'; ros2 param load would take only '/rm_robot:'
    path = tmp_path / 'robot.yaml'
    path.write_text(yaml.safe_dump({
        'other': {'ros__parameters': {'loop': {'kp': 99.0}}},
        '/**': {'ros__parameters': {'loop': {'kp': 1.0}}},
        'tuned': {'ros__parameters': {'loop': {'kp': 7}}},  # an integer, as set reads it
    }))
    code, out, err = rmcli('param', 'load', '/tuned', str(path))
    assert (code, out) == (0, 'Set parameter loop.kp successful\n'), err
    assert tuned.get_parameter('loop.kp').value == 7.0
    # a name the node does not declare is refused by the node and said plainly; the rest
    # of the file still loads (one undeclared name used to make the node answer no values)
    path.write_text(yaml.safe_dump({'tuned': {'ros__parameters': {
        'loop': {'kp': 6.0}, 'nobody': {'gain': 1.0}}}}))
    code, out, err = rmcli('param', 'load', '/tuned', str(path))
    assert code == 1, err
    assert sorted(out.splitlines()) == [
        'Set parameter loop.kp successful',
        'Set parameter nobody.gain failed: /tuned has no such parameter',
    ]
    assert tuned.get_parameter('loop.kp').value == 6.0


@pytest.mark.parametrize(('text', 'says'), [
    ('tuned:\n  ros__parameters:\n    loop.kp: [\n', 'line 4, column 1: not YAML'),
    ('other:\n  ros__parameters:\n    loop.kp: 1.0\n', 'no parameters for /tuned'),
    ('tuned:\n  ros__parameters:\n    loop.kp:\n', 'loop.kp has no value'),
    ('tuned:\n  ros__parameters:\n    loop.limits: [1, 2.0, x]\n', 'loop.limits'),
])
def test_a_bad_parameter_file_is_one_line_and_sets_nothing(tuned, tmp_path, text, says):
    path = tmp_path / 'bad.yaml'
    path.write_text(text)
    code, out, err = rmcli('param', 'load', '/tuned', str(path))
    assert code == 1 and out == ''
    assert err.startswith(f'rmcli: error: {path}: ') and says in err, err
    assert len(err.splitlines()) == 1, err
    assert tuned.get_parameter('loop.kp').value == 2.0


def test_a_node_that_is_not_there_is_one_line_and_exit_1(ros_context):
    code, _, err = rmcli('param', 'list', '/nobody', '--timeout', '1')
    assert code == 1 and err == 'rmcli: error: node not found: /nobody (waited 1 s)\n'
