"""Launch the robot: can_bridge and rm_robot, both from one robot config.

    ros2 launch rm_bringup robot.launch.py                          # standard, real buses
    ros2 launch rm_bringup robot.launch.py robot:=standard sim:=true   # on rm_sim
    ros2 launch rm_bringup robot.launch.py config:=/path/my_robot.yaml

Arguments:
    robot: installed robot config, share/rm_bringup/config/<robot>.yaml (default standard).
    config: path of a robot config file instead (its overlay: <name>_sim.yaml beside it).
    sim: true loads the simulation overlay after the config (every bus on rm_sim).

The same files `bringup --robot <robot> [--sim]` loads, in the same order, given to both
nodes as --params-file (each node reads its own section). For a real ROS 2 Jazzy install;
the virtualenv has no launch (use `bringup` or `make run` there).

DDS discovery stays on this machine (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST) unless the
variable is already set: set SUBNET on a robot that talks to other machines.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction, SetEnvironmentVariable
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

DISCOVERY_RANGE_VAR = 'ROS_AUTOMATIC_DISCOVERY_RANGE'


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


def _nodes(context, *args, **kwargs):
    robot = LaunchConfiguration('robot').perform(context)
    config = LaunchConfiguration('config').perform(context)
    sim = LaunchConfiguration('sim').perform(context) == 'true'
    files = parameter_files(robot, config, sim)
    return [
        Node(
            package='rm_base',
            executable='can_bridge',
            name='can_bridge',
            parameters=files,
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
            description='run every bus on the simulated CAN interface rm_sim',
        ),
    ]
    if DISCOVERY_RANGE_VAR not in os.environ:
        actions.append(SetEnvironmentVariable(DISCOVERY_RANGE_VAR, 'LOCALHOST'))
    actions.append(OpaqueFunction(function=_nodes))
    return LaunchDescription(actions)
