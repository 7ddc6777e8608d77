"""Jam detection for a trigger (loader) motor: high effort, no motion, for too long.

A jammed trigger pushes against a stuck bullet: its speed loop saturates the effort
while the speed stays near zero. A short spike of the same kind is normal (a bullet
seating), so the condition must hold for a while. The detector counts time from the dt
of each step, not the wall clock, so it behaves the same in a replay or the simulator.
"""

import math
from dataclasses import dataclass

from rm_base.control.validation import require_non_negative, require_positive
from rm_base.errors import InputRejectedError

# Summing dt rounds: ten steps of 0.01 s add up to 0.09999999999999999 s, which must still
# count as 0.1 s.
_TIME_TOLERANCE_S = 1e-9


@dataclass(frozen=True, slots=True)
class JamDetectorParams:
    """When a trigger counts as jammed.

    Attributes:
        effort_threshold: |effort| above this counts as pushing [N·m, or A: whatever the
            effort passed to update is in], > 0.
        speed_threshold: |speed| below this counts as stalled [rad/s], > 0.
        time_s: How long both must hold before it is a jam [s], >= 0.
    """

    effort_threshold: float
    speed_threshold: float
    time_s: float

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(
            self,
            'effort_threshold',
            require_positive(owner, 'effort_threshold', self.effort_threshold),
        )
        object.__setattr__(
            self,
            'speed_threshold',
            require_positive(owner, 'speed_threshold', self.speed_threshold),
        )
        object.__setattr__(self, 'time_s', require_non_negative(owner, 'time_s', self.time_s))


class JamDetector:
    """Detects a stalled trigger that keeps pushing.

    Jammed once |effort| > effort_threshold and |speed| < speed_threshold have held
    together for at least time_s; cleared as soon as either condition stops holding.
    Magnitudes are compared, so a stall while reversing (BLOCK) is caught as well.
    """

    __slots__ = ('_elapsed_s', '_params')

    def __init__(self, params: JamDetectorParams) -> None:
        """Create a detector with no time counted."""
        if not isinstance(params, JamDetectorParams):
            raise TypeError(f'params must be a JamDetectorParams, got {type(params).__name__}')
        self._params = params
        self._elapsed_s = 0.0

    @property
    def params(self) -> JamDetectorParams:
        """The thresholds."""
        return self._params

    @property
    def stalled_s(self) -> float:
        """How long the stall condition has held without a break [s]."""
        return self._elapsed_s

    @property
    def jammed(self) -> bool:
        """True if the last update found a jam."""
        elapsed = self._elapsed_s
        return elapsed > 0.0 and elapsed + _TIME_TOLERANCE_S >= self._params.time_s

    def reset(self) -> None:
        """Forget the counted time (e.g. after clearing a jam, or on enable)."""
        self._elapsed_s = 0.0

    def update(self, effort: float, speed: float, dt: float) -> bool:
        """Account for one step and return whether the trigger is jammed.

        Args:
            effort: Trigger effort this step (torque [N·m] or current [A]).
            speed: Measured trigger speed [rad/s].
            dt: Time since the previous update [s], finite and > 0.

        Returns:
            True while jammed.

        Raises:
            InputRejectedError: If effort or speed is NaN or infinite, or dt is not finite
                and > 0. The state is left as it was.
        """
        if not 0.0 < dt < math.inf:
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        if not (math.isfinite(effort) and math.isfinite(speed)):
            raise InputRejectedError(f'effort and speed must be finite, got {effort!r}, {speed!r}')
        params = self._params
        if abs(effort) > params.effort_threshold and abs(speed) < params.speed_threshold:
            self._elapsed_s += dt
        else:
            self._elapsed_s = 0.0
        return self.jammed
