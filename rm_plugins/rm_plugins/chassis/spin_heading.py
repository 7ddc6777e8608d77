"""GYRO's closed heading loop: the chassis' heading follows the spin it was asked for.

Open loop, GYRO asks the wheels for a spin rate and trusts the wheels' speed loops to give
it. A wheel that drags or slips (a bump, a wheel lifted off the ground, a jammed bearing)
then changes the chassis' turn at once, and nothing brings it back. The loop here keeps a
*reference heading* that advances at the spin rate asked for (after its ramp) and adds a
correction to that rate in proportion to how far the measured heading (odometry, from the
IMU when there is one) lags or leads it::

    reference += rate_asked(previous step) * dt
    error = wrap(reference - heading), kept within ±max_error
    wz = rate_asked + gain * error

The error is kept within ``max_error`` by moving the reference (a chassis held against a
wall does not wind the loop up and then whirl when released), so the correction is never
more than ``gain * max_error``. A gain of 0 is the open loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rm_base.control.validation import require_non_negative, require_positive
from rm_base.errors import InputRejectedError
from rm_base.geometry.angles import wrap_to_pi


@dataclass(frozen=True, slots=True)
class SpinHeadingParams:
    """Gains of :class:`SpinHeadingLoop`.

    Attributes:
        gain: correction of the spin rate per radian of heading error [1/s], >= 0; 0 is
            the open loop.
        max_error: largest heading error the loop acts on [rad], > 0.
    """

    gain: float = 0.0
    max_error: float = 0.5

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(self, 'gain', require_non_negative(owner, 'gain', self.gain))
        object.__setattr__(
            self, 'max_error', require_positive(owner, 'max_error', self.max_error)
        )


#: No heading loop: the spin is what the wheels' speed loops give.
OPEN_LOOP = SpinHeadingParams()


class SpinHeadingLoop:
    """The heading loop of one spin; :meth:`reset` when the spin ends."""

    __slots__ = ('_error', '_params', '_rate', '_reference')

    def __init__(self, params: SpinHeadingParams) -> None:
        self._params = params
        self.reset()

    @property
    def error(self) -> float:
        """The heading error of the last update [rad] (reference minus measured)."""
        return self._error

    def set_params(self, params: SpinHeadingParams) -> None:
        """New gain and error bound (set while running), from the next update on."""
        self._params = params

    def reset(self) -> None:
        """Forget the reference: the next update takes the measured heading as its start."""
        self._reference: float | None = None
        self._rate = 0.0
        self._error = 0.0

    def update(self, rate: float, heading: float, dt: float) -> float:
        """Return the spin rate to command [rad/s].

        Args:
            rate: the spin rate asked for this step [rad/s] (after its ramp).
            heading: the chassis' measured heading [rad] (any reference, unwrapped or not).
            dt: time since the previous update [s], > 0.

        Raises:
            InputRejectedError: a value is NaN or infinite, or dt <= 0.
        """
        if not all(map(math.isfinite, (rate, heading))) or not 0.0 < dt < math.inf:
            raise InputRejectedError(
                f'spin rate, heading and dt must be finite (dt > 0), got {rate!r}, '
                f'{heading!r}, {dt!r}'
            )
        params = self._params
        if self._reference is None:
            self._reference = heading
        else:
            self._reference += self._rate * dt
        error = wrap_to_pi(self._reference - heading)
        if abs(error) > params.max_error:
            error = math.copysign(params.max_error, error)
            self._reference = heading + error
        self._rate = rate
        self._error = error
        return rate + params.gain * error
