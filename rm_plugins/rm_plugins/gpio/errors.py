"""Errors of the GPIO plugin and its backends."""

from rm_base.errors import ConfigError, InputRejectedError, RmError


class GpioError(RmError):
    """Base of the GPIO errors."""


class GpioConfigError(GpioError, ConfigError):
    """A pin is configured wrongly.

    Example: a PWM pin without ``pwm_channel``, or a simulated switch window wider than a
    slot.
    """


class GpioBackendError(GpioError):
    """A backend cannot be opened or a line cannot be used.

    Example: the ``linux`` backend on a machine without the ``gpiod`` package, or
    ``/dev/gpiochip0`` missing or busy.
    """


class GpioCommandError(GpioError, InputRejectedError):
    """A GpioCmd was rejected: unknown pin, an input pin, or a value out of range or NaN."""
