"""Errors of the plugin framework: loading, configuring, initialising and running plugins.

Configuration problems are ``ConfigError`` subclasses whose message names the plugin
instance, its type and the offending key, so the host can print one line instead of a
traceback. Runtime input problems are ``InputRejectedError`` subclasses.
"""

from rm_base.errors import ConfigError, InputRejectedError, RmError


class PluginConfigError(ConfigError):
    """A plugin cannot be set up from the robot config.

    Attributes:
        plugin: instance name from the robot config (e.g. ``chassis``), or '' if unknown.
    """

    def __init__(self, message: str, *, plugin: str = '') -> None:
        super().__init__(message)
        self.plugin = plugin


class PluginNotFoundError(PluginConfigError):
    """No installed package declares a plugin of the requested type.

    Example: ``chassis.type: rm_plugins/StandChasis`` (typo), or the package that
    provides the plugin was not built or its ``setup.bash`` not sourced.
    """


class PluginDescriptionError(PluginConfigError):
    """A plugin description XML is malformed or names a class that cannot be imported.

    Example: the XML says ``type="rm_extra.counter.Counter"`` but the module has no
    ``Counter`` class, or the class does not derive from ``PluginBase``.
    """


class PluginInitError(PluginConfigError):
    """A plugin raised while initialising (not a parameter problem).

    Example: a serial IMU plugin cannot open its port.
    """


class ParameterError(PluginConfigError):
    """A parameter is missing, of the wrong type, or out of range.

    Attributes:
        key: the full parameter name (e.g. ``chassis.wheel_radius``).
    """

    def __init__(self, message: str, *, plugin: str = '', key: str = '') -> None:
        super().__init__(message, plugin=plugin)
        self.key = key


class JointClaimError(PluginConfigError):
    """Two plugins claim the same joint, or a plugin commands a joint it did not claim.

    Example: the gimbal and the chassis both list ``yaw_joint``.
    """


class TransitionError(RmError):
    """A state machine was asked for a transition its table does not allow.

    Example: a shooter going straight from PASSIVE to PUSH without FEED and READY.
    """


class TargetRejectedError(InputRejectedError):
    """Joint targets were not published because one of them is invalid.

    Example: a NaN velocity from a division by a zero wheel radius.
    """
