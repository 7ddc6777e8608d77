"""Launch the robot from one robot config: one process by default, or split in nodes.

    ros2 launch rm_bringup robot.launch.py                          # standard, real buses
    ros2 launch rm_bringup robot.launch.py robot:=standard sim:=true   # on rm_sim
    ros2 launch rm_bringup robot.launch.py config:=/path/my_robot.yaml
    ros2 launch rm_bringup robot.launch.py split:=true              # can_bridge + rm_robot

Arguments:
    robot: installed robot config, share/rm_bringup/config/<robot>.yaml (default standard).
    config: path of a robot config file instead (its overlay: <name>_sim.yaml beside it).
    sim: true runs every bus on rm_sim, the simulated motors (a process of their own).
    split: true runs can_bridge and rm_robot as two processes, /actuator_cmd between them
        over DDS (only to split a robot across machines); default false: ``bringup``, the
        one-process robot whose plugins run in the CAN loop.

One process: ``bringup --config <file> [--sim] --no-status``. Split: the files (the config,
then with sim its overlay) given to both nodes as --params-file (each node reads its own
section) and, with sim, rm_sim beside them and the bridge's buses on ``rm_sim_socket``.
For a real ROS 2 Jazzy install; the virtualenv has no launch (use `bringup` or `make run`
there).

DDS discovery stays on this machine (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST) unless the
variable is already set: set SUBNET on a robot that talks to other machines.
"""

import os

import yaml
from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction, SetEnvironmentVariable
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

DISCOVERY_RANGE_VAR = 'ROS_AUTOMATIC_DISCOVERY_RANGE'


#: The operator's commander, started when the robot config has a section for it.
MANUAL_NODE_NAME = 'rm_manual'


def has_section(files: list[str], node: str) -> bool:
    """Whether a parameter file has a section for node."""
    for path in files:
        with open(path) as stream:
            if node in (yaml.safe_load(stream) or {}):
                return True
    return False


def parameter_files(robot: str, config: str, sim: bool) -> list[str]:
    """The parameter files of a robot: its config, then (sim) its simulation overlay."""
    if config:
        base = os.path.abspath(os.path.expanduser(config))
    else:
        share = get_package_share_directory('rm_bringup')
        base = os.path.join(share, 'config', f'{robot}.yaml')
    if not os.path.isfile(base):
        raise RuntimeError(f'robot config {base} not found')
    files = [base]
    if sim:
        stem, _ = os.path.splitext(base)
        overlay = f'{stem}_sim.yaml'
        if not os.path.isfile(overlay):
            raise RuntimeError(f'sim:=true needs the simulation overlay {overlay} (missing)')
        files.append(overlay)
    return files


def bus_names(files: list[str]) -> list[str]:
    """The buses of the can_bridge section of the files."""
    buses: set[str] = set()
    for path in files:
        with open(path) as stream:
            document = yaml.safe_load(stream) or {}
        section = (document.get('can_bridge') or {}).get('ros__parameters', {})
        buses.update(section.get('buses', {}))
    return sorted(buses)


def _nodes(context, *args, **kwargs):
    robot = LaunchConfiguration('robot').perform(context)
    config = LaunchConfiguration('config').perform(context)
    sim = LaunchConfiguration('sim').perform(context) == 'true'
    split = LaunchConfiguration('split').perform(context) == 'true'
    files = parameter_files(robot, config, sim)
    if not split:
        return [
            Node(
                package='rm_bringup',
                executable='bringup',
                arguments=['--config', files[0], '--no-status', *(['--sim'] if sim else [])],
                output='screen',
                emulate_tty=True,
            )
        ]
    nodes = []
    bridge_parameters = list(files)
    if sim:
        # rm_sim listens on its default socket (per ROS_DOMAIN_ID), where rm_sim_socket
        # looks by default; the bridge retries its buses until rm_sim is up.
        arguments = []
        for path in files:
            arguments += ['--params-file', path]
        nodes.append(
            Node(package='rm_base', executable='rm_sim', arguments=arguments, output='screen')
        )
        bridge_parameters.append(
            {'sim': False, **{f'buses.{b}.interface': 'rm_sim_socket' for b in bus_names(files)}}
        )
    nodes += [
        Node(
            package='rm_base',
            executable='can_bridge',
            name='can_bridge',
            parameters=bridge_parameters,
            output='screen',
            emulate_tty=True,
        ),
        Node(
            package='rm_base',
            executable='rm_robot',
            name='rm_robot',
            parameters=files,
            output='screen',
            emulate_tty=True,
        ),
    ]
    if has_section(files, MANUAL_NODE_NAME):
        # the operator's commander: rm_robot's executable as a host of its own
        nodes.append(
            Node(
                package='rm_base',
                executable='rm_robot',
                name=MANUAL_NODE_NAME,
                parameters=files,
                output='screen',
                emulate_tty=True,
            )
        )
    return nodes


def generate_launch_description():
    actions = [
        DeclareLaunchArgument(
            'robot', default_value='standard', description='installed robot config name'
        ),
        DeclareLaunchArgument(
            'config', default_value='', description='robot config file (instead of robot)'
        ),
        DeclareLaunchArgument(
            'sim',
            default_value='false',
            choices=['true', 'false'],
            description='run every bus on rm_sim, the simulated motors',
        ),
        DeclareLaunchArgument(
            'split',
            default_value='false',
            choices=['true', 'false'],
            description='can_bridge and rm_robot as two processes (DDS between them)',
        ),
    ]
    if DISCOVERY_RANGE_VAR not in os.environ:
        actions.append(SetEnvironmentVariable(DISCOVERY_RANGE_VAR, 'LOCALHOST'))
    actions.append(OpaqueFunction(function=_nodes))
    return LaunchDescription(actions)
