"""The interface every GPIO backend implements."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping

from rm_plugins.gpio.pins import PinKind, PinSpec


class GpioBackend(ABC):
    """Reads and writes the configured pins of one plugin.

    A backend is opened with every pin at once (its constructor) and used from one thread
    (the plugin's run thread). Values are checked by the caller (``check_command``) before
    they reach ``write``. ``close`` is idempotent; a backend is also a context manager.

    Args:
        pins: the pins by name.
    """

    def __init__(self, pins: Mapping[str, PinSpec]) -> None:
        self.pins = dict(pins)

    @abstractmethod
    def read(self, name: str) -> float:
        """Return the value of pin name: 0/1 for digital pins, the duty cycle for PWM.

        For outputs this is the value last written (the initial value before that).
        """

    @abstractmethod
    def write(self, name: str, value: float) -> None:
        """Set output name to 0/1, or PWM name to a duty cycle in [0, 1]."""

    def close(self) -> None:  # noqa: B027 (optional hook: nothing to release by default)
        """Release the hardware. Default: nothing."""

    def reset_outputs(self) -> None:
        """Write every output and PWM pin's initial value (the safe state)."""
        for spec in self.pins.values():
            if spec.kind is not PinKind.INPUT:
                self.write(spec.name, spec.initial)

    def __enter__(self) -> GpioBackend:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
