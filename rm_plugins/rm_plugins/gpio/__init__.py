"""GPIO plugin (``rm_plugins/UpboardGpio``): named inputs, outputs and PWM through a backend.

Backends: ``SimGpioBackend`` (outputs recorded, inputs from models such as the shooter's
ball switch, ``JointPhaseSwitch``) and ``LinuxGpioBackend`` (libgpiod v2 lines, sysfs PWM).
"""

from rm_plugins.gpio.backend import GpioBackend
from rm_plugins.gpio.errors import (
    GpioBackendError,
    GpioCommandError,
    GpioConfigError,
    GpioError,
)
from rm_plugins.gpio.linux_backend import LinuxGpioBackend
from rm_plugins.gpio.pins import (
    Bias,
    ConstantInput,
    DigitalLine,
    JointPhaseSwitch,
    PinKind,
    PinSpec,
    PwmChannel,
    check_command,
    value_problem,
)
from rm_plugins.gpio.plugin import BackendKind, SimModel, UpboardGpio
from rm_plugins.gpio.sim_backend import SimGpioBackend

__all__ = [
    'BackendKind',
    'Bias',
    'ConstantInput',
    'DigitalLine',
    'GpioBackend',
    'GpioBackendError',
    'GpioCommandError',
    'GpioConfigError',
    'GpioError',
    'JointPhaseSwitch',
    'LinuxGpioBackend',
    'PinKind',
    'PinSpec',
    'PwmChannel',
    'SimGpioBackend',
    'SimModel',
    'UpboardGpio',
    'check_command',
    'value_problem',
]
