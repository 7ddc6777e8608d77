"""The rm_ros2 plugin framework: PluginBase, its state machine, parameters, I/O and loader.

A plugin author needs ``PluginBase`` and the helpers it hands out (``PluginParams``,
``CommandInput``, ``JointTarget``, the joint-state view); the host needs ``PluginLoader``.
"""

from rm_base.config.schema import REQUIRED
from rm_base.joints import JointState, JointTarget, Mode
from rm_base.plugin.base import STATE_QOS, PluginBase
from rm_base.plugin.commands import CommandInput, CommandStatus, LatestMessage, LogThrottle
from rm_base.plugin.errors import (
    JointClaimError,
    ParameterError,
    PluginConfigError,
    PluginDescriptionError,
    PluginInitError,
    PluginNotFoundError,
    TargetRejectedError,
    TransitionError,
)
from rm_base.plugin.joints import JointStateView, build_actuator_cmd
from rm_base.plugin.loader import BASE_CLASS_TYPE, PluginDescription, PluginLoader
from rm_base.plugin.node_io import ACTUATOR_CMD_TOPIC, ACTUATOR_STATES_TOPIC
from rm_base.plugin.params import PluginParams
from rm_base.plugin.state_machine import DefaultState, StateMachine, Transition

__all__ = [
    'ACTUATOR_CMD_TOPIC',
    'ACTUATOR_STATES_TOPIC',
    'BASE_CLASS_TYPE',
    'REQUIRED',
    'STATE_QOS',
    'CommandInput',
    'CommandStatus',
    'DefaultState',
    'JointClaimError',
    'JointState',
    'JointStateView',
    'JointTarget',
    'LatestMessage',
    'LogThrottle',
    'Mode',
    'ParameterError',
    'PluginBase',
    'PluginConfigError',
    'PluginDescription',
    'PluginDescriptionError',
    'PluginInitError',
    'PluginLoader',
    'PluginNotFoundError',
    'PluginParams',
    'StateMachine',
    'TargetRejectedError',
    'Transition',
    'TransitionError',
    'build_actuator_cmd',
]
