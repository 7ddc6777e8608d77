"""The rm_robot plugin host node: ``RobotHost``, its per-plugin runners and ``main``."""

from rm_base.host.node import NODE_NAME, ExecutorKind, RobotHost
from rm_base.host.runner import PluginRunner

__all__ = ['NODE_NAME', 'ExecutorKind', 'PluginRunner', 'RobotHost']
