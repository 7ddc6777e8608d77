"""The rm_robot plugin host node: ``RobotHost``, its loop tasks and ``main``."""

from rm_base.host.node import NODE_NAME, ExecutorKind, RobotHost
from rm_base.host.plugin_task import PluginTask, TickInputs

__all__ = ['NODE_NAME', 'ExecutorKind', 'PluginTask', 'RobotHost', 'TickInputs']
