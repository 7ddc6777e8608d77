"""Root of the rm_ros2 exception tree.

Each subpackage defines its own errors (in its ``errors.py``) as subclasses of these, so
callers can catch a whole family (``except ConfigError``) or everything (``RmError``).
"""


class RmError(Exception):
    """Base of every error raised on purpose by rm_ros2."""


class ConfigError(RmError, ValueError):
    """A configuration or parameter is missing, of the wrong type, or out of range.

    Example: a robot config names a motor type that does not exist, or omits a wheel radius.
    """


class InputRejectedError(RmError, ValueError):
    """A runtime input (command, target, frame) is invalid and was not used.

    Example: a NaN velocity target, an unknown chassis mode, a CAN frame with a wrong length.
    """
