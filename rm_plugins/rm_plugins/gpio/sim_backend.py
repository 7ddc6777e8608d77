"""Simulated GPIO: outputs are recorded, inputs are played by a model of the robot."""

from __future__ import annotations

from collections.abc import Callable, Mapping

from rm_plugins.gpio.backend import GpioBackend
from rm_plugins.gpio.pins import ConstantInput, JointPhaseSwitch, PinKind, PinSpec


class SimGpioBackend(GpioBackend):
    """GPIO for the simulator (and for a robot without GPIO hardware).

    Outputs and PWM duty cycles are kept and read back, so /gpio_state shows what was
    commanded. An input reads its model: a ``ConstantInput`` its value, a
    ``JointPhaseSwitch`` 1 while its joint's phase is inside the window (0 while the joint
    has not been seen yet).

    Args:
        pins: the pins by name.
        joint_position: returns a joint's latest position [rad], or None if unknown.
    """

    def __init__(
        self,
        pins: Mapping[str, PinSpec],
        joint_position: Callable[[str], float | None],
    ) -> None:
        super().__init__(pins)
        self._joint_position = joint_position
        self._outputs = {
            name: spec.initial for name, spec in self.pins.items() if spec.kind is not PinKind.INPUT
        }

    def read(self, name: str) -> float:
        """Return an input's model value, or the value last written to an output."""
        spec = self.pins[name]
        if spec.kind is not PinKind.INPUT:
            return self._outputs[name]
        model = spec.sim
        if isinstance(model, ConstantInput):
            return model.value
        if isinstance(model, JointPhaseSwitch):
            position = self._joint_position(model.joint)
            return 1.0 if position is not None and model.closed(position) else 0.0
        raise TypeError(f'pin {name!r}: unknown simulated input model {model!r}')

    def write(self, name: str, value: float) -> None:
        """Record an output's value or a PWM duty cycle."""
        if self.pins[name].kind is PinKind.INPUT:
            raise ValueError(f'pin {name!r} is an input')
        self._outputs[name] = float(value)
