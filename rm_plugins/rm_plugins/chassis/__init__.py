"""StandChassis: the mecanum/omni chassis plugin (rm_plugins/StandChassis) and its parts.

The plugin orchestrates; the parts are plain Python without ROS: command checking
(``commands``), parameters (``config``), ramps/modes/kinematics (``motion``), wheel speed
loops with the power limit (``wheels``) and odometry (``odometry``).
"""

from rm_plugins.chassis.commands import (
    ChassisMode,
    ChassisRequest,
    FollowSource,
    parse_chassis_cmd,
    parse_vel_cmd,
)
from rm_plugins.chassis.config import ChassisConfig, ImuMount, Kinematics, read_config
from rm_plugins.chassis.motion import MotionOutput, MotionPlanner
from rm_plugins.chassis.odometry import Odometry, Pose2D, YawSource
from rm_plugins.chassis.plugin import StandChassis

__all__ = [
    'ChassisConfig',
    'ChassisMode',
    'ChassisRequest',
    'FollowSource',
    'ImuMount',
    'Kinematics',
    'MotionOutput',
    'MotionPlanner',
    'Odometry',
    'Pose2D',
    'StandChassis',
    'YawSource',
    'parse_chassis_cmd',
    'parse_vel_cmd',
    'read_config',
]
