"""Pin descriptions (what the config says) and command checks for the GPIO plugin.

A pin has a name (used on /gpio_cmd and /gpio_state) and a kind: a digital INPUT, a
digital OUTPUT (0 or 1) or a PWM output (duty cycle in [0, 1]). Where it lives on the
hardware (a line of a GPIO character device, a sysfs PWM channel) and how the simulator
plays an input are parts of the description too; each backend uses the parts it needs.
No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import Enum, IntEnum

from rm_msgs.msg import GpioState
from rm_plugins.gpio.errors import GpioCommandError, GpioConfigError

#: A rejection names at most this many bad entries, and a pin name at most this long.
_MAX_PROBLEMS = 3
_MAX_NAME = 40


def _short(name: str) -> str:
    if len(name) <= _MAX_NAME:
        return repr(name)
    return f'{name[:_MAX_NAME]!r}... ({len(name)} characters)'


class PinKind(IntEnum):
    """What a pin does; the values are rm_msgs/GpioState's INPUT/OUTPUT/PWM."""

    INPUT = GpioState.INPUT
    OUTPUT = GpioState.OUTPUT
    PWM = GpioState.PWM


class Bias(Enum):
    """Internal bias of a digital line (as libgpiod's ``line.Bias``)."""

    AS_IS = 'as_is'
    DISABLED = 'disabled'
    PULL_UP = 'pull_up'
    PULL_DOWN = 'pull_down'


@dataclass(frozen=True)
class DigitalLine:
    """A line of a Linux GPIO character device.

    Attributes:
        chip: the device, e.g. ``/dev/gpiochip0``.
        offset: the line's offset on that chip.
        active_low: the line reads/writes 1 when the pin is low (e.g. a switch to ground
            with a pull-up).
        bias: internal pull-up/down.
    """

    chip: str
    offset: int
    active_low: bool = False
    bias: Bias = Bias.AS_IS


@dataclass(frozen=True)
class PwmChannel:
    """A channel of a sysfs PWM chip (``/sys/class/pwm/pwmchip<chip>/pwm<channel>``).

    Attributes:
        chip: the PWM chip number.
        channel: the channel on that chip.
        frequency: PWM frequency [Hz], > 0.
    """

    chip: int
    channel: int
    frequency: float


@dataclass(frozen=True)
class ConstantInput:
    """Simulated input that always reads ``value`` (0 or 1)."""

    value: float = 0.0


@dataclass(frozen=True)
class JointPhaseSwitch:
    """Simulated limit switch closed while a joint's phase lies in a window.

    The model of the shooter's ball switch: the trigger (loader wheel) has ``slots``
    pockets, one ball in each (an endless hopper); the switch sits at the firing position
    and closes while a pocket, with its ball, is in front of it. With the slot angle
    ``s = 2*pi / slots``, the phase ``p = position mod s`` (in [0, s)) says where the
    nearest pocket is, so the switch is closed iff ``window[0] <= p <= window[1]``: a ball
    arrives each time the trigger turns into a slot, whichever way it turned.

    Attributes:
        joint: the joint, read from /actuator_states (never claimed).
        slots: pockets per turn, >= 1.
        window: (low, high) phase [rad], 0 <= low < high <= 2*pi / slots.
    """

    joint: str
    slots: int
    window: tuple[float, float]

    def __post_init__(self) -> None:
        if isinstance(self.slots, bool) or not isinstance(self.slots, int) or self.slots < 1:
            raise GpioConfigError(f'sim_slots must be an integer >= 1, got {self.slots!r}')
        low, high = self.window
        if not (0.0 <= low < high <= self.slot_angle):
            raise GpioConfigError(
                f'sim_window must satisfy 0 <= low < high <= 2*pi/slots = '
                f'{self.slot_angle:.4f} rad, got [{low}, {high}]'
            )

    @property
    def slot_angle(self) -> float:
        """Angle between two pockets [rad]."""
        return 2.0 * math.pi / self.slots

    def phase(self, position: float) -> float:
        """Return position modulo the slot angle, in [0, slot_angle) [rad]."""
        slot = self.slot_angle
        phase = position - slot * math.floor(position / slot)
        return phase if phase < slot else 0.0

    def closed(self, position: float) -> bool:
        """Return whether the switch is closed with the joint at position [rad]."""
        low, high = self.window
        return low <= self.phase(position) <= high


SimInput = ConstantInput | JointPhaseSwitch


@dataclass(frozen=True)
class PinSpec:
    """One configured pin.

    Attributes:
        name: name on /gpio_cmd and /gpio_state.
        kind: input, output or PWM.
        initial: value at start-up and after disable (outputs: 0/1; PWM: duty in [0, 1]).
        line: where a digital pin is on the hardware (linux backend).
        pwm: where a PWM pin is on the hardware (linux backend).
        sim: how the simulated backend plays an input.
    """

    name: str
    kind: PinKind
    initial: float = 0.0
    line: DigitalLine | None = None
    pwm: PwmChannel | None = None
    sim: SimInput = ConstantInput()

    def __post_init__(self) -> None:
        if self.kind is not PinKind.INPUT:
            problem = value_problem(self.kind, self.initial)
            if problem:
                raise GpioConfigError(f'pin {self.name!r}: initial value {problem}')

    def digital_line(self) -> DigitalLine:
        """The hardware line of a digital pin (the linux backend's config requires it)."""
        if self.line is None:
            raise GpioConfigError(f'pin {self.name!r}: no line configured')
        return self.line

    def pwm_channel(self) -> PwmChannel:
        """The hardware channel of a PWM pin (the linux backend's config requires it)."""
        if self.pwm is None:
            raise GpioConfigError(f'pin {self.name!r}: no PWM channel configured')
        return self.pwm


def value_problem(kind: PinKind, value: float) -> str | None:
    """Return why value cannot be written to a pin of kind, or None if it can.

    Digital outputs take exactly 0 or 1; PWM pins a duty cycle in [0, 1]; inputs nothing.
    """
    if kind is PinKind.INPUT:
        return 'cannot be set: the pin is an input'
    try:
        number = float(value)
    except (TypeError, ValueError):
        return f'{value!r} is not a number'
    if not math.isfinite(number):
        return f'{number} is not a finite number'
    if kind is PinKind.OUTPUT and number not in (0.0, 1.0):
        return f'{number} is not 0 or 1 (digital output)'
    if kind is PinKind.PWM and not 0.0 <= number <= 1.0:
        return f'{number} is outside the duty cycle range [0, 1]'
    return None


def check_command(
    pins: Mapping[str, PinSpec], names: Sequence[str], values: Sequence[float]
) -> dict[str, float]:
    """Check one GpioCmd as a whole; return {pin: value} to write.

    All or nothing: one bad entry rejects the whole command, so a half-applied command
    never leaves the outputs in a state nobody asked for.

    Raises:
        GpioCommandError: names and values differ in length, a name is listed twice or is
            unknown, a pin is an input, or a value is NaN/inf or out of range; the message
            lists every problem.
    """
    if len(names) != len(values):
        raise GpioCommandError(f'rejected /gpio_cmd: {len(names)} names but {len(values)} values')
    problems = []
    writes: dict[str, float] = {}
    for name, value in zip(names, values, strict=True):
        spec = pins.get(name)
        if spec is None:
            problems.append(f'unknown pin {_short(name)} (known: {", ".join(sorted(pins))})')
            continue
        if name in writes:
            problems.append(f'pin {name!r} listed twice')
            continue
        problem = value_problem(spec.kind, value)
        if problem:
            problems.append(f'pin {name!r}: {problem}')
            continue
        writes[name] = float(value)
    if problems:
        # the first few, and a count: a flood of bad entries must not make a log line of MBs
        more = len(problems) - _MAX_PROBLEMS
        said = '; '.join(problems[:_MAX_PROBLEMS]) + (f'; and {more} more' if more > 0 else '')
        raise GpioCommandError(f'rejected /gpio_cmd ({len(names)} entries): {said}')
    return writes
