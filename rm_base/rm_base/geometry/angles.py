"""Angle wrapping and shortest signed differences, in radians.

All functions take and return plain floats. They are exact for angles already in range
(returned unchanged) and use ``math.remainder``, which is exact, outside it, so wrapping
adds no rounding error of its own.
"""

import math

from rm_base.errors import InputRejectedError

TAU = 2.0 * math.pi
"""One full turn [rad]."""


def _require_finite(name: str, value: float) -> None:
    if not math.isfinite(value):
        raise InputRejectedError(f'{name} must be a finite angle in rad, got {value!r}')


def wrap_to_pi(angle: float) -> float:
    """Wrap an angle to [-pi, pi).

    Args:
        angle: Angle [rad], any finite value.

    Returns:
        The equivalent angle in [-pi, pi) [rad]; +pi maps to -pi.

    Raises:
        InputRejectedError: If angle is NaN or infinite.
    """
    if -math.pi <= angle < math.pi:
        return angle
    _require_finite('angle', angle)
    # remainder() returns angle - n*TAU for the nearest integer n, exactly, in [-pi, pi].
    wrapped = math.remainder(angle, TAU)
    return wrapped - TAU if wrapped >= math.pi else wrapped


def wrap_to_2pi(angle: float) -> float:
    """Wrap an angle to [0, 2*pi).

    Args:
        angle: Angle [rad], any finite value.

    Returns:
        The equivalent angle in [0, 2*pi) [rad].

    Raises:
        InputRejectedError: If angle is NaN or infinite.
    """
    if 0.0 <= angle < TAU:
        return angle
    _require_finite('angle', angle)
    wrapped = math.remainder(angle, TAU)
    if wrapped < 0.0:
        wrapped += TAU
        # A tiny negative remainder rounds up to exactly TAU, which is out of range; the
        # nearest in-range value is 0.
        if wrapped >= TAU:
            wrapped = 0.0
    return wrapped


def shortest_angular_distance(from_angle: float, to_angle: float) -> float:
    """Return the signed rotation that takes from_angle to to_angle the shortest way round.

    Positive is counter-clockwise (REP 103). Same argument order as ROS ``angles``.

    Args:
        from_angle: Start angle [rad].
        to_angle: End angle [rad].

    Returns:
        ``to_angle - from_angle`` wrapped to [-pi, pi) [rad]; exactly half a turn gives -pi.

    Raises:
        InputRejectedError: If either angle is NaN or infinite.
    """
    _require_finite('from_angle', from_angle)
    _require_finite('to_angle', to_angle)
    return wrap_to_pi(to_angle - from_angle)
