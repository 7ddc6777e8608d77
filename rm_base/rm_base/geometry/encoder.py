"""Unwrapping of single-turn absolute encoder ticks into a continuous multi-turn angle.

DJI motors report the rotor angle as 0..8191 ticks per turn; MIT-mode and other motors
use other resolutions. Between two samples the shaft is assumed to turn less than half
a turn, so the shorter way round between the two readings is the true motion.

All angles here are of the encoder shaft (the rotor for DJI motors). The output shaft of
a geared motor turns ``gear_ratio`` times slower: see :func:`rotor_to_output`.
"""

import math
import operator

from rm_base.errors import ConfigError, InputRejectedError

DJI_TICKS_PER_REV = 8192
"""Resolution of DJI C610/C620/GM6020 rotor angle feedback [ticks/rev]."""


class EncoderUnwrapper:
    """Turns successive tick readings into a multi-turn angle [rad] without drift.

    The count is kept as an integer number of ticks, so any number of turns is exact.
    The first sample initialises: the multi-turn angle starts at that sample's
    single-turn angle, in [0, 2*pi).

    Example:
        >>> encoder = EncoderUnwrapper(8192)
        >>> round(encoder.update(8000), 6)  # first sample: 8000 ticks
        6.135923
        >>> round(encoder.update(100), 6)  # +292 ticks across the wrap, not -7900
        6.359884
    """

    __slots__ = ('_half', '_last_ticks', '_rad_per_tick', '_ticks_per_rev', '_total_ticks')

    def __init__(self, ticks_per_rev: int = DJI_TICKS_PER_REV) -> None:
        """Create an unwrapper waiting for its first sample.

        Args:
            ticks_per_rev: Encoder resolution [ticks/rev]; raw readings are
                0..ticks_per_rev-1. At least 4 (half a turn must be more than a tick).

        Raises:
            ConfigError: If ticks_per_rev is not an integer >= 4.
        """
        if isinstance(ticks_per_rev, bool) or not isinstance(ticks_per_rev, int):
            raise ConfigError(f'ticks_per_rev must be an integer, got {ticks_per_rev!r}')
        if ticks_per_rev < 4:
            raise ConfigError(f'ticks_per_rev must be >= 4, got {ticks_per_rev}')
        self._ticks_per_rev = ticks_per_rev
        self._half = ticks_per_rev // 2
        self._rad_per_tick = 2.0 * math.pi / ticks_per_rev
        self.reset()

    def reset(self) -> None:
        """Forget the history; the next sample initialises again."""
        self._last_ticks: int | None = None
        self._total_ticks = 0

    def update(self, ticks: int) -> float:
        """Take a new reading and return the multi-turn angle.

        Args:
            ticks: Raw reading, an integer in 0..ticks_per_rev-1.

        Returns:
            Multi-turn angle [rad]; positive is the encoder's counting direction.

        Raises:
            InputRejectedError: If ticks is not an integer or is out of range. The state
                is left as it was.
        """
        try:
            ticks = operator.index(ticks)  # int and numpy integers; floats are refused
        except TypeError:
            raise InputRejectedError(f'encoder ticks must be an integer, got {ticks!r}') from None
        if not 0 <= ticks < self._ticks_per_rev:
            raise InputRejectedError(
                f'encoder ticks must be in 0..{self._ticks_per_rev - 1}, got {ticks}'
            )
        last = self._last_ticks
        if last is None:
            self._total_ticks = ticks
        else:
            delta = ticks - last
            # The shorter way round; exactly half a turn counts as backwards.
            if delta >= self._half:
                delta -= self._ticks_per_rev
            elif delta < -self._half:
                delta += self._ticks_per_rev
            self._total_ticks += delta
        self._last_ticks = ticks
        return self._total_ticks * self._rad_per_tick

    @property
    def ticks_per_rev(self) -> int:
        """Encoder resolution [ticks/rev]."""
        return self._ticks_per_rev

    @property
    def initialized(self) -> bool:
        """Whether a sample has been taken since construction or reset."""
        return self._last_ticks is not None

    @property
    def total_ticks(self) -> int | None:
        """Multi-turn position in ticks, or None before the first sample."""
        return None if self._last_ticks is None else self._total_ticks

    @property
    def angle(self) -> float | None:
        """Multi-turn angle [rad], or None before the first sample."""
        if self._last_ticks is None:
            return None
        return self._total_ticks * self._rad_per_tick

    @property
    def single_turn_angle(self) -> float | None:
        """Angle of the last reading within one turn, in [0, 2*pi) [rad], or None."""
        if self._last_ticks is None:
            return None
        return self._last_ticks * self._rad_per_tick

    @property
    def turns(self) -> int | None:
        """Whole turns counted from tick 0 (floor, so -1 just below zero), or None."""
        if self._last_ticks is None:
            return None
        return self._total_ticks // self._ticks_per_rev


def rotor_to_output(rotor_value: float, gear_ratio: float) -> float:
    """Convert a rotor angle or speed to the output shaft of a gearbox.

    Args:
        rotor_value: Rotor angle [rad] or speed [rad/s].
        gear_ratio: Rotor turns per output turn, e.g. 3591/187 (about 19.2) for an M3508;
            negative if the gearbox reverses the direction.

    Returns:
        The output-shaft value, same unit.

    Raises:
        ConfigError: If gear_ratio is zero, NaN or infinite.
    """
    if not math.isfinite(gear_ratio) or gear_ratio == 0.0:
        raise ConfigError(f'gear_ratio must be finite and non-zero, got {gear_ratio!r}')
    return rotor_value / gear_ratio
