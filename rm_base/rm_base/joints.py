"""The joint vocabulary every layer speaks: modes, targets and states (output shaft, SI).

Plugins set :class:`JointTarget` s, the bridge parses them out of rm_msgs/ActuatorCmd,
the hardware layer applies them, and all of them report :class:`JointState` s. A target
is checked once, where it enters (a plugin's ``send_joint_targets``, an /actuator_cmd
message, ``CanHardware.set_command``), by :func:`check_target`, and trusted after. Units
follow REP 103: rad, rad/s, N·m, °C. No rclpy and no message types here.
"""

from __future__ import annotations

import enum
import math
import numbers
from dataclasses import dataclass
from typing import NamedTuple

from rm_base.errors import InputRejectedError


class Mode(enum.IntEnum):
    """How a joint is driven; the values are rm_msgs/ActuatorCmd's MODE_*."""

    OFF = 0  # no output: zero current, the joint is limp
    EFFORT = 1  # effort [N·m] as given
    VELOCITY = 2  # velocity [rad/s], PID at the loop rate
    POSITION = 3  # position [rad], cascade position -> velocity (+ velocity feed-forward)
    MIT = 4  # tau = kp*(position - q) + kd*(velocity - dq) + effort


# The message's names for the modes.
MODE_OFF = Mode.OFF
MODE_EFFORT = Mode.EFFORT
MODE_VELOCITY = Mode.VELOCITY
MODE_POSITION = Mode.POSITION
MODE_MIT = Mode.MIT


@dataclass(frozen=True, slots=True)
class JointTarget:
    """Target of one joint.

    Attributes:
        mode: how the fields below are used.
        position: [rad] (POSITION, MIT).
        velocity: [rad/s] (VELOCITY; MIT; feed-forward in POSITION).
        effort: [N·m] (EFFORT; feed-forward in MIT).
        kp: [N·m/rad] >= 0, MIT only.
        kd: [N·m·s/rad] >= 0, MIT only.
    """

    mode: Mode
    position: float = 0.0
    velocity: float = 0.0
    effort: float = 0.0
    kp: float = 0.0
    kd: float = 0.0

    @classmethod
    def off(cls) -> JointTarget:
        """No output: the joint goes limp."""
        return cls(Mode.OFF)

    @classmethod
    def with_effort(cls, effort: float) -> JointTarget:
        """Effort control at effort [N·m]."""
        return cls(Mode.EFFORT, effort=effort)

    @classmethod
    def with_velocity(cls, velocity: float) -> JointTarget:
        """Velocity control at velocity [rad/s]."""
        return cls(Mode.VELOCITY, velocity=velocity)

    @classmethod
    def with_position(cls, position: float, velocity: float = 0.0) -> JointTarget:
        """Position control at position [rad] with an optional velocity feed-forward [rad/s]."""
        return cls(Mode.POSITION, position=position, velocity=velocity)

    @classmethod
    def with_mit(
        cls, position: float, velocity: float, effort: float, kp: float, kd: float
    ) -> JointTarget:
        """MIT impedance control (see ``Mode.MIT``)."""
        return cls(Mode.MIT, position, velocity, effort, kp, kd)


class TargetProblem(enum.Enum):
    """What made a joint target invalid; the values name the bridge's rejection counters."""

    UNKNOWN_MODE = 'unknown_mode'
    NON_FINITE = 'non_finite'  # a field is NaN, infinite, or not a number at all
    NEGATIVE_GAIN = 'negative_gain'


class InvalidTargetError(InputRejectedError):
    """A joint target that must not reach a motor.

    Example: ``check_target(Mode.EFFORT, effort=float('nan'))``.

    Attributes:
        problem: which rule it broke.
    """

    def __init__(self, problem: TargetProblem, message: str) -> None:
        super().__init__(message)
        self.problem = problem


_MODES = {int(mode): mode for mode in Mode}


def check_target(
    mode: object,
    *,
    position: object = 0.0,
    velocity: object = 0.0,
    effort: object = 0.0,
    kp: object = 0.0,
    kd: object = 0.0,
) -> JointTarget:
    """Return the validated target, every field a float and the mode a Mode.

    The messages do not name the joint: the caller, who knows where the target came
    from, does.

    Raises:
        InvalidTargetError: unknown mode, a field that is not a finite number (a bool is
            not a number here), or a negative MIT gain.
    """
    checked = _MODES.get(mode) if isinstance(mode, int) and not isinstance(mode, bool) else None
    if checked is None:
        raise InvalidTargetError(
            TargetProblem.UNKNOWN_MODE, f'unknown mode {mode!r} (MODE_OFF..MODE_MIT)'
        )
    values = (position, velocity, effort, kp, kd)
    # Every tick of every plugin comes through here: the common case in one pass.
    if all(type(v) is float and math.isfinite(v) for v in values):
        p, v, e, k, d = values
    else:
        p, v, e, k, d = (
            _number(name, value) for name, value in zip(_FIELDS, values, strict=True)
        )
    if k < 0.0 or d < 0.0:  # type: ignore[operator]
        raise InvalidTargetError(
            TargetProblem.NEGATIVE_GAIN, f'MIT gains must be >= 0, got kp={k}, kd={d}'
        )
    return JointTarget(checked, p, v, e, k, d)  # type: ignore[arg-type]


def checked(target: object) -> JointTarget:
    """Validate a JointTarget built elsewhere (its fields are whatever its maker gave).

    Raises:
        InvalidTargetError: as :func:`check_target`, or target is no JointTarget.
    """
    if type(target) is JointTarget:
        # Every plugin target of every tick: one that is already valid is returned as it
        # is (frozen). A finite sum means every field is finite; anything else goes the
        # long way, which names the field.
        p, v, e, k, d = target.position, target.velocity, target.effort, target.kp, target.kd
        if (type(target.mode) is Mode and type(p) is float and type(v) is float
                and type(e) is float and type(k) is float and type(d) is float
                and math.isfinite(p + v + e + k + d) and k >= 0.0 and d >= 0.0):
            return target
    elif not isinstance(target, JointTarget):
        raise InvalidTargetError(
            TargetProblem.UNKNOWN_MODE, f'not a JointTarget: {target!r}'
        )
    return check_target(
        target.mode, position=target.position, velocity=target.velocity,
        effort=target.effort, kp=target.kp, kd=target.kd,
    )


_FIELDS = ('position', 'velocity', 'effort', 'kp', 'kd')


def _number(field: str, value: object) -> float:
    # any real number (numpy scalars too), but not a bool
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidTargetError(
            TargetProblem.NON_FINITE, f'{field} must be a number, got {value!r}'
        )
    number = float(value)
    if not math.isfinite(number):
        raise InvalidTargetError(
            TargetProblem.NON_FINITE, f'{field} is not a finite number: {value!r}'
        )
    return number


class JointState(NamedTuple):
    """One joint's state, fields as rm_msgs/ActuatorState.

    Attributes:
        name: joint name.
        position: [rad], continuous (multi-turn).
        velocity: [rad/s].
        effort: [N·m] measured.
        temperature: [°C]; NaN where the device reports none (C610).
        online: feedback seen within the feedback timeout.
        error_code: device error code, 0 = none.
        mode: the mode actually applied (OFF while the joint is held safe).
        command: effort actually commanded [N·m], after every clamp.
        stamp_ns: when it was measured [ns], on the clock of whoever reports it (the
            hardware's in ``CanHardware.states()``, the node's in a plugin's view); 0 when
            never.
    """

    name: str
    position: float
    velocity: float
    effort: float
    temperature: float
    online: bool
    error_code: int
    mode: int
    command: float
    stamp_ns: int = 0
