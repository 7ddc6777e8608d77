"""rm_bringup/launch/robot.launch.py, executed against small fake launch/launch_ros modules.

launch and launch_ros are not on PyPI, so the venv cannot import them. The launch file
imports them normally (it only runs on a real ROS install); here ``launch``,
``launch.actions``, ``launch.substitutions``, ``launch_ros``, ``launch_ros.actions`` and
``ament_index_python.packages`` are replaced in sys.modules by fakes that record the
actions, and the launch file's OpaqueFunction is run with a fake context holding the
launch arguments. The fake share folder is the source tree of rm_bringup, which has the
installed layout (config/*.yaml).
"""

from __future__ import annotations

import importlib.util
import pathlib
import sys
import types

import pytest

BRINGUP = pathlib.Path(__file__).resolve().parents[3] / 'rm_bringup'
LAUNCH_FILE = BRINGUP / 'launch' / 'robot.launch.py'
CONFIG = BRINGUP / 'config'
VAR = 'ROS_AUTOMATIC_DISCOVERY_RANGE'


class Recorded:
    """A fake launch action: keeps its arguments."""

    def __init__(self, *args, **kwargs):
        self.args = args
        self.kwargs = kwargs


class LaunchDescription(Recorded):
    @property
    def entities(self):
        return list(self.args[0])


class DeclareLaunchArgument(Recorded):
    pass


class OpaqueFunction(Recorded):
    pass


class SetEnvironmentVariable(Recorded):
    pass


class Node(Recorded):
    pass


class LaunchConfiguration:
    def __init__(self, name):
        self.name = name

    def perform(self, context):
        return context.launch_configurations[self.name]


class Context:
    def __init__(self, configurations):
        self.launch_configurations = dict(configurations)


def fake_modules(share_dirs: dict[str, pathlib.Path]) -> dict[str, types.ModuleType]:
    def module(name, **members):
        mod = types.ModuleType(name)
        mod.__dict__.update(members)
        return mod

    def get_package_share_directory(package):
        return str(share_dirs[package])

    return {
        'launch': module('launch', LaunchDescription=LaunchDescription),
        'launch.actions': module(
            'launch.actions',
            DeclareLaunchArgument=DeclareLaunchArgument,
            OpaqueFunction=OpaqueFunction,
            SetEnvironmentVariable=SetEnvironmentVariable,
        ),
        'launch.substitutions': module(
            'launch.substitutions', LaunchConfiguration=LaunchConfiguration
        ),
        'launch_ros': module('launch_ros'),
        'launch_ros.actions': module('launch_ros.actions', Node=Node),
        'ament_index_python.packages': module(
            'ament_index_python.packages', get_package_share_directory=get_package_share_directory
        ),
    }


@pytest.fixture
def launch_file(monkeypatch):
    """The launch module, loaded with the fakes in place."""
    for name, mod in fake_modules({'rm_bringup': BRINGUP}).items():
        monkeypatch.setitem(sys.modules, name, mod)
    spec = importlib.util.spec_from_file_location('robot_launch', LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def launch(module, **arguments):
    """Run generate_launch_description() and its OpaqueFunction(s) like `ros2 launch`.

    Returns (top-level actions, actions returned by the opaque functions).
    """
    entities = module.generate_launch_description().entities
    declared = {
        a.args[0]: a.kwargs.get('default_value')
        for a in entities
        if isinstance(a, DeclareLaunchArgument)
    }
    unknown = set(arguments) - set(declared)
    assert not unknown, f'not declared: {unknown}'
    context = Context({**declared, **arguments})
    produced = []
    for action in entities:
        if isinstance(action, OpaqueFunction):
            function = action.kwargs['function']
            produced.extend(
                function(context, *action.kwargs.get('args', ()), **action.kwargs.get('kwargs', {}))
            )
    return entities, produced


def nodes_by_executable(produced):
    """The nodes by name (rm_manual runs rm_robot's executable)."""
    nodes = [a for a in produced if isinstance(a, Node)]
    return {n.kwargs.get('name', n.kwargs['executable']): n.kwargs for n in nodes}


def test_when_launched_with_defaults_expect_the_one_process_robot_on_the_standard_config(
    launch_file,
):
    _, produced = launch(launch_file)
    nodes = nodes_by_executable(produced)
    assert set(nodes) == {'bringup'}
    assert nodes['bringup']['package'] == 'rm_bringup'
    config = str(CONFIG / 'standard.yaml')
    assert nodes['bringup']['arguments'] == ['--config', config, '--no-status']


def test_when_sim_is_true_expect_bringup_to_start_rm_sim(launch_file):
    _, produced = launch(launch_file, robot='standard', sim='true')
    arguments = nodes_by_executable(produced)['bringup']['arguments']
    assert arguments == ['--config', str(CONFIG / 'standard.yaml'), '--no-status', '--sim']


def test_when_split_expect_bridge_and_host_on_the_standard_config(launch_file):
    _, produced = launch(launch_file, split='true')
    nodes = nodes_by_executable(produced)
    # the operator's commander (rm_manual) is a host of its own: rm_robot's executable
    assert set(nodes) == {'can_bridge', 'rm_robot', 'rm_manual'}
    assert nodes['rm_manual']['executable'] == 'rm_robot'
    for name, node in nodes.items():
        assert node['package'] == 'rm_base'
        assert node['name'] == name  # the config's sections are named after the nodes
        assert node['parameters'] == [str(CONFIG / 'standard.yaml')]


def test_when_split_on_the_sim_expect_rm_sim_and_the_bridge_on_its_socket(launch_file):
    _, produced = launch(launch_file, robot='standard', sim='true', split='true')
    expected = [str(CONFIG / 'standard.yaml'), str(CONFIG / 'standard_sim.yaml')]
    nodes = nodes_by_executable(produced)
    assert set(nodes) == {'rm_sim', 'can_bridge', 'rm_robot', 'rm_manual'}
    assert nodes['rm_sim']['arguments'] == [
        '--params-file', expected[0], '--params-file', expected[1],
    ]
    assert nodes['can_bridge']['parameters'] == [
        *expected,
        {'sim': False, 'buses.can0.interface': 'rm_sim_socket',
         'buses.can1.interface': 'rm_sim_socket'},
    ]
    assert nodes['rm_robot']['parameters'] == expected
    assert nodes['rm_manual']['parameters'] == expected
    assert all(pathlib.Path(p).is_file() for p in expected)


def test_the_arguments_are_declared_with_their_defaults(launch_file):
    entities, _ = launch(launch_file)
    declared = {a.args[0]: a.kwargs for a in entities if isinstance(a, DeclareLaunchArgument)}
    assert declared['robot']['default_value'] == 'standard'
    assert declared['sim']['default_value'] == 'false'
    assert declared['sim']['choices'] == ['true', 'false']
    assert declared['config']['default_value'] == ''
    assert declared['split']['default_value'] == 'false'
    # The arguments come before the function that reads them.
    opaque = next(i for i, a in enumerate(entities) if isinstance(a, OpaqueFunction))
    assert all(i < opaque for i, a in enumerate(entities) if isinstance(a, DeclareLaunchArgument))


def test_when_discovery_range_is_unset_expect_localhost_set_before_the_nodes(
    launch_file, monkeypatch
):
    monkeypatch.delenv(VAR, raising=False)
    entities, _ = launch(launch_file)
    settings = [a for a in entities if isinstance(a, SetEnvironmentVariable)]
    assert [s.args for s in settings] == [(VAR, 'LOCALHOST')]
    opaque = next(i for i, a in enumerate(entities) if isinstance(a, OpaqueFunction))
    assert entities.index(settings[0]) < opaque


def test_when_discovery_range_is_set_expect_it_left_alone(launch_file, monkeypatch):
    monkeypatch.setenv(VAR, 'SUBNET')
    entities, _ = launch(launch_file)
    assert not [a for a in entities if isinstance(a, SetEnvironmentVariable)]


def test_when_a_config_file_is_given_expect_it_and_its_overlay_beside_it(launch_file, tmp_path):
    robot = tmp_path / 'my_robot.yaml'
    robot.write_text('can_bridge: {ros__parameters: {}}\n')
    (tmp_path / 'my_robot_sim.yaml').write_text('can_bridge: {ros__parameters: {sim: true}}\n')
    _, produced = launch(launch_file, config=str(robot), sim='true', split='true')
    node = nodes_by_executable(produced)['rm_robot']
    assert node['parameters'] == [str(robot), str(tmp_path / 'my_robot_sim.yaml')]


def test_when_the_robot_is_unknown_expect_an_error_naming_the_file(launch_file):
    with pytest.raises(RuntimeError, match=r'robot config .*no_such_robot\.yaml not found'):
        launch(launch_file, robot='no_such_robot')


def test_when_sim_has_no_overlay_expect_an_error_naming_it(launch_file, tmp_path):
    robot = tmp_path / 'bare.yaml'
    robot.write_text('rm_robot: {ros__parameters: {}}\n')
    message = r'sim:=true needs the simulation overlay .*bare_sim\.yaml \(missing\)'
    with pytest.raises(RuntimeError, match=message):
        launch(launch_file, config=str(robot), sim='true')


def test_the_launch_file_is_installed_into_the_share_folder():
    from ament_index_python.packages import get_package_share_directory

    share = pathlib.Path(get_package_share_directory('rm_bringup'))
    installed = share / 'launch' / 'robot.launch.py'
    assert installed.is_file(), 'run scripts/setup.sh after adding a launch file'
    assert installed.read_text() == LAUNCH_FILE.read_text()
