"""The CAN bridge node: the rclpy edge over :mod:`rm_base.hardware` (``can_bridge``).

``params`` turns ROS parameters into the hardware config, ``sim_config`` the simulated
world of sim mode, ``sim_services`` its fault services, ``commands`` validates
/actuator_cmd, ``messages`` and ``diagnostics`` build what the node publishes, ``frames``
taps every CAN frame; ``node`` holds :class:`CanBridgeNode` and ``main`` the executable.
"""

from rm_base.bridge.commands import parse_actuator_cmd
from rm_base.bridge.diagnostics import CommandStats, DiagnosticsReporter
from rm_base.bridge.errors import ActuatorCmdRejectedError, BridgeConfigError, Rejection
from rm_base.bridge.frames import FrameTap, TappedFrame
from rm_base.bridge.node import NODE_NAME, CanBridgeNode
from rm_base.bridge.params import BridgeSettings, SimSettings, settings_from_parameters
from rm_base.bridge.sim_config import motor_config, world_config
from rm_base.bridge.sim_services import SIM_FAULTS, SimFaultServices
from rm_base.joints import JointTarget

__all__ = [
    'NODE_NAME',
    'SIM_FAULTS',
    'ActuatorCmdRejectedError',
    'BridgeConfigError',
    'BridgeSettings',
    'CanBridgeNode',
    'CommandStats',
    'DiagnosticsReporter',
    'FrameTap',
    'JointTarget',
    'Rejection',
    'SimFaultServices',
    'SimSettings',
    'TappedFrame',
    'motor_config',
    'parse_actuator_cmd',
    'settings_from_parameters',
    'world_config',
]
