"""Errors of the CAN bridge node (``rm_base.bridge``).

The tree, rooted at :class:`rm_base.errors.RmError`::

    BridgeConfigError (ConfigError)        a parameter set that cannot become a config
    ActuatorCmdRejectedError (InputRejectedError)   an /actuator_cmd message not applied
    PowerLimitRejectedError (InputRejectedError)    a /power_limit message not applied

Errors of the layers below keep their own types (``HardwareConfigError``,
``SimConfigError``); all configuration errors are ``ConfigError``, so ``main`` prints one
line for any of them.
"""

from __future__ import annotations

import enum

from rm_base.errors import ConfigError, InputRejectedError


class BridgeConfigError(ConfigError):
    """The bridge's parameters cannot be turned into a hardware or simulator config.

    Example: ``joints.yaw: 3`` beside ``joints.yaw.id: 1``, an unknown top-level
    parameter ``publish_rat``, or ``sim: true`` with a Piper joint (no simulated model).
    """


class Rejection(enum.Enum):
    """Why an /actuator_cmd message was not applied; the value names its counter."""

    LENGTH_MISMATCH = 'length_mismatch'  # arrays of unequal length
    DUPLICATE_JOINT = 'duplicate_joint'  # one joint named twice
    UNKNOWN_JOINT = 'unknown_joint'  # a name this bridge does not drive
    UNKNOWN_MODE = 'unknown_mode'  # a mode outside ActuatorCmd.MODE_*
    NON_FINITE = 'non_finite'  # NaN or inf in any value
    NEGATIVE_GAIN = 'negative_gain'  # kp or kd < 0
    STALE = 'stale'  # header stamp older than the command timeout (or as far in the future)
    OLD_STATES = 'old_states'  # computed from states older than this bridge's first


class ActuatorCmdRejectedError(InputRejectedError):
    """An /actuator_cmd message was rejected as a whole; no joint of it was changed.

    Example: ``name: [wheel_fl, wheel_fr]`` with ``velocity: [1.0]``, or a NaN effort.

    Attributes:
        reason: the :class:`Rejection` kind (the counter it goes to).
    """

    def __init__(self, reason: Rejection, message: str) -> None:
        super().__init__(message)
        self.reason = reason


class PowerLimitRejectedError(InputRejectedError):
    """A /power_limit message was rejected; the stage it named stays as it was.

    Example: a joint the bridge does not drive, or a negative ``k1``.
    """
