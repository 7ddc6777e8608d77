"""Linux GPIO: digital lines through libgpiod v2, PWM through the kernel's sysfs PWM class.

Digital lines use the GPIO character device (``/dev/gpiochipN``) through the ``gpiod``
package, the official Python bindings of libgpiod v2 (the sysfs GPIO interface is
deprecated). libgpiod has no PWM; for PWM we use ``python-periphery``'s ``PWM`` class, a
small, maintained wrapper of ``/sys/class/pwm/pwmchipN/pwmM`` (export, period, duty cycle,
enable) with no dependencies of its own. The UP board exposes its header PWM there.

Both packages are imported only when this backend is built, and only if a pin needs them,
so the simulator and the tests need neither. They are not in the project's lock file: a
robot installs them (``pip install gpiod python-periphery``) beside the system's libgpiod.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from types import ModuleType
from typing import Any

from rm_plugins.gpio.backend import GpioBackend
from rm_plugins.gpio.errors import GpioBackendError, GpioConfigError
from rm_plugins.gpio.pins import Bias, PinKind, PinSpec

#: Consumer label shown by ``gpioinfo`` for the lines we hold.
DEFAULT_CONSUMER = 'rm_robot'

_GPIOD_HINT = (
    "the linux GPIO backend needs the Python package 'gpiod' (libgpiod v2 bindings, "
    'gpiod >= 2.0): pip install gpiod'
)
_PERIPHERY_HINT = (
    "PWM pins on the linux GPIO backend need the Python package 'python-periphery' "
    '(module periphery): pip install python-periphery'
)


def _import(module: str, hint: str) -> ModuleType:
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise GpioBackendError(f'{hint} ({type(err).__name__}: {err})') from err


class LinuxGpioBackend(GpioBackend):
    """GPIO character device lines (libgpiod v2) and sysfs PWM channels (python-periphery).

    One line request per chip holds all of that chip's configured lines for the life of
    the backend (``close`` releases them; so does the process ending). Outputs start at
    their initial value; PWM channels are set to their frequency and initial duty cycle and
    enabled.

    Args:
        pins: the pins by name; digital pins need ``line``, PWM pins ``pwm``.
        consumer: consumer label of the line requests.

    Raises:
        GpioConfigError: a digital pin without a line, or a PWM pin without a channel.
        GpioBackendError: a needed package is missing or too old, or a chip, line or PWM
            channel cannot be opened; the message names the pin.
    """

    def __init__(self, pins: Mapping[str, PinSpec], consumer: str = DEFAULT_CONSUMER) -> None:
        super().__init__(pins)
        self._requests: dict[str, Any] = {}  # chip path -> gpiod.LineRequest
        self._pwms: dict[str, Any] = {}  # pin name -> periphery.PWM
        self._gpiod: ModuleType | None = None  # imported when a digital pin needs it
        self._written = {
            name: spec.initial for name, spec in self.pins.items() if spec.kind is not PinKind.INPUT
        }
        digital = {n: s for n, s in self.pins.items() if s.kind is not PinKind.PWM}
        pwm = {n: s for n, s in self.pins.items() if s.kind is PinKind.PWM}
        for name, spec in digital.items():
            if spec.line is None:
                raise GpioConfigError(f'pin {name!r}: a digital pin needs a line (chip, offset)')
        for name, spec in pwm.items():
            if spec.pwm is None:
                raise GpioConfigError(f'pin {name!r}: a PWM pin needs pwm_chip and pwm_channel')
        try:
            if digital:
                self._open_lines(digital, consumer)
            if pwm:
                self._open_pwms(pwm)
        except BaseException:
            self.close()
            raise

    # -- GpioBackend ------------------------------------------------------------------------

    def read(self, name: str) -> float:
        """Return an input's line level, or the value last written to an output."""
        spec = self.pins[name]
        if spec.kind is not PinKind.INPUT:
            return self._written[name]
        line = spec.digital_line()
        request = self._requests[line.chip]
        try:
            value = request.get_value(line.offset)
        except Exception as err:
            raise GpioBackendError(f'pin {name!r}: cannot read line: {err}') from err
        return 1.0 if value == self._gpiod_module().line.Value.ACTIVE else 0.0

    def write(self, name: str, value: float) -> None:
        """Drive an output line, or set a PWM channel's duty cycle."""
        spec = self.pins[name]
        try:
            if spec.kind is PinKind.OUTPUT:
                levels = self._gpiod_module().line.Value
                digital = spec.digital_line()
                self._requests[digital.chip].set_value(
                    digital.offset, levels.ACTIVE if value else levels.INACTIVE
                )
            elif spec.kind is PinKind.PWM:
                self._pwms[name].duty_cycle = float(value)
            else:
                raise ValueError(f'pin {name!r} is an input')
        except ValueError:
            raise
        except Exception as err:
            raise GpioBackendError(f'pin {name!r}: cannot write {value}: {err}') from err
        self._written[name] = float(value)

    def _gpiod_module(self) -> ModuleType:
        if self._gpiod is None:  # no digital pin was opened
            raise GpioBackendError('no digital pin is configured')
        return self._gpiod

    def close(self) -> None:
        """Release every line request and PWM channel (PWM disabled first). Idempotent."""
        for name, pwm in list(self._pwms.items()):
            try:
                pwm.disable()
                pwm.close()
            except Exception:  # closing: nothing better to do than go on
                pass
            del self._pwms[name]
        for chip, request in list(self._requests.items()):
            try:
                request.release()
            except Exception:  # as above
                pass
            del self._requests[chip]

    # -- set-up -----------------------------------------------------------------------------

    def _open_lines(self, pins: Mapping[str, PinSpec], consumer: str) -> None:
        gpiod = _import('gpiod', _GPIOD_HINT)
        if not hasattr(gpiod, 'request_lines') or not hasattr(gpiod, 'LineSettings'):
            version = getattr(gpiod, '__version__', 'unknown')
            raise GpioBackendError(f'{_GPIOD_HINT}; found gpiod {version} (the v1 API)')
        self._gpiod = gpiod
        line = gpiod.line
        biases = {
            Bias.AS_IS: line.Bias.AS_IS,
            Bias.DISABLED: line.Bias.DISABLED,
            Bias.PULL_UP: line.Bias.PULL_UP,
            Bias.PULL_DOWN: line.Bias.PULL_DOWN,
        }
        by_chip: dict[str, dict[int, Any]] = {}
        owner: dict[tuple[str, int], str] = {}
        for name, spec in pins.items():
            digital = spec.digital_line()
            key = (digital.chip, digital.offset)
            if key in owner:
                raise GpioConfigError(
                    f'pins {owner[key]!r} and {name!r} are both line {key[1]} of {key[0]}'
                )
            owner[key] = name
            if spec.kind is PinKind.INPUT:
                settings = gpiod.LineSettings(
                    direction=line.Direction.INPUT,
                    active_low=digital.active_low,
                    bias=biases[digital.bias],
                )
            else:
                settings = gpiod.LineSettings(
                    direction=line.Direction.OUTPUT,
                    active_low=digital.active_low,
                    bias=biases[digital.bias],
                    output_value=line.Value.ACTIVE if spec.initial else line.Value.INACTIVE,
                )
            by_chip.setdefault(digital.chip, {})[digital.offset] = settings
        for chip, config in by_chip.items():
            names = ', '.join(owner[(chip, offset)] for offset in config)
            try:
                self._requests[chip] = gpiod.request_lines(chip, consumer=consumer, config=config)
            except Exception as err:
                raise GpioBackendError(
                    f'cannot request lines {sorted(config)} of {chip} for pin(s) {names}: '
                    f'{type(err).__name__}: {err}'
                ) from err

    def _open_pwms(self, pins: Mapping[str, PinSpec]) -> None:
        periphery = _import('periphery', _PERIPHERY_HINT)
        for name, spec in pins.items():
            channel = spec.pwm_channel()
            try:
                pwm = periphery.PWM(channel.chip, channel.channel)
            except Exception as err:
                raise GpioBackendError(
                    f'pin {name!r}: cannot open PWM chip {channel.chip} channel '
                    f'{channel.channel}: {type(err).__name__}: {err}'
                ) from err
            self._pwms[name] = pwm
            try:
                # A new period shorter than the current duty time is refused by the kernel,
                # so clear the duty time first.
                pwm.duty_cycle_ns = 0
                pwm.frequency = channel.frequency
                pwm.duty_cycle = spec.initial
                pwm.enable()
            except Exception as err:
                raise GpioBackendError(
                    f'pin {name!r}: cannot set up PWM chip {channel.chip} channel '
                    f'{channel.channel} at {channel.frequency} Hz: {type(err).__name__}: {err}'
                ) from err
