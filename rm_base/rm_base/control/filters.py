"""Small scalar filters: first-order low-pass and moving average."""

import math
from collections import deque

from rm_base.control.validation import require_positive
from rm_base.errors import ConfigError, InputRejectedError


class LowPassFilter:
    """First-order low-pass ``tau * dy/dt + y = x``, discretised exactly for any dt.

    ``y += (x - y) * (1 - exp(-dt / tau))``, which holds x constant over the step, so the
    response does not depend on how the time is split into steps. The first sample after
    construction or :meth:`reset` initialises the output (no start-up transient).
    """

    __slots__ = ('_tau', '_value')

    def __init__(self, time_constant_s: float) -> None:
        """Create a filter.

        Args:
            time_constant_s: Time constant tau [s], > 0; the -3 dB cutoff is
                1 / (2 * pi * tau) Hz.

        Raises:
            ConfigError: If time_constant_s is not finite and > 0.
        """
        self._tau = require_positive('LowPassFilter', 'time_constant_s', time_constant_s)
        self._value: float | None = None

    @classmethod
    def from_cutoff_hz(cls, cutoff_hz: float) -> 'LowPassFilter':
        """Create a filter from its -3 dB cutoff frequency [Hz], > 0."""
        cutoff_hz = require_positive('LowPassFilter', 'cutoff_hz', cutoff_hz)
        return cls(1.0 / (2.0 * math.pi * cutoff_hz))

    @property
    def time_constant_s(self) -> float:
        """Time constant tau [s]."""
        return self._tau

    @property
    def value(self) -> float | None:
        """Filtered value, or None before the first sample."""
        return self._value

    def reset(self, value: float | None = None) -> None:
        """Restart at value, or (None) initialise on the next sample.

        Raises:
            InputRejectedError: If value is NaN or infinite.
        """
        if value is not None and not math.isfinite(value):
            raise InputRejectedError(f'filter value must be finite, got {value!r}')
        self._value = value

    def update(self, sample: float, dt: float) -> float:
        """Filter one sample taken dt after the previous one and return the output.

        Args:
            sample: New input x.
            dt: Time since the previous sample [s], finite and > 0.

        Returns:
            The filtered value, same units as sample.

        Raises:
            InputRejectedError: If sample is NaN/inf, or dt is not finite and > 0.
        """
        if not 0.0 < dt < math.inf:
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        if not math.isfinite(sample):
            raise InputRejectedError(f'filter sample must be finite, got {sample!r}')
        value = self._value
        if value is None:
            value = sample
        else:
            value -= (sample - value) * math.expm1(-dt / self._tau)
        self._value = value
        return value


class MovingAverage:
    """Mean of the last ``window`` samples (fewer until the window has filled)."""

    __slots__ = ('_samples',)

    def __init__(self, window: int) -> None:
        """Create an empty average.

        Args:
            window: Number of samples averaged, >= 1.

        Raises:
            ConfigError: If window is not an integer >= 1.
        """
        if isinstance(window, bool) or not isinstance(window, int) or window < 1:
            raise ConfigError(f'MovingAverage.window must be an integer >= 1, got {window!r}')
        self._samples: deque[float] = deque(maxlen=window)

    @property
    def window(self) -> int:
        """Number of samples averaged once full."""
        return self._samples.maxlen  # type: ignore[return-value]

    @property
    def value(self) -> float | None:
        """Current mean, or None before the first sample."""
        if not self._samples:
            return None
        return math.fsum(self._samples) / len(self._samples)

    def reset(self) -> None:
        """Forget every sample."""
        self._samples.clear()

    def update(self, sample: float) -> float:
        """Add a sample and return the mean of the window.

        Raises:
            InputRejectedError: If sample is NaN or infinite (it is not added).
        """
        if not math.isfinite(sample):
            raise InputRejectedError(f'moving-average sample must be finite, got {sample!r}')
        self._samples.append(sample)
        # fsum over the window instead of a running sum: no drift however long it runs.
        return math.fsum(self._samples) / len(self._samples)
