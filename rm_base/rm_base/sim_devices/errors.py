"""Errors of the simulator (``rm_base.sim``).

The tree, rooted at :class:`rm_base.errors.RmError`::

    SimError
    ├── SimConfigError (also ConfigError)   bad motor/world/IMU config, id collision
    ├── SimLookupError (also LookupError)   no motor or channel of that name
    └── SimStateError                       an operation that the simulator's state forbids

python-can's own errors (``can.CanOperationError``) are raised where python-can callers
expect them, e.g. a send on a closed bus or on a bus with an injected bus-off.
"""

from rm_base.errors import ConfigError, RmError


class SimError(RmError):
    """Base of every error raised on purpose by ``rm_base.sim``."""


class SimConfigError(SimError, ConfigError):
    """A simulator configuration is invalid.

    Example: a motor of type ``m3509``, two DJI motors that share a command slot on one
    channel, a negative inertia, or an IMU mounted on a body that does not exist.
    """


class SimLookupError(SimError, LookupError):
    """No simulated motor or channel has that name.

    Example: ``world.motor('wheel_fx')`` when the config names ``wheel_fl``.
    """


class SimStateError(SimError):
    """The simulator's current state forbids the operation.

    Example: ``world.step()`` while the real-time physics thread owns the clock.
    """
