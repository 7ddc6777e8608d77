"""Fixed-rate events on the simulation clock (integer nanoseconds, no drift)."""

_NS_PER_S = 1_000_000_000


class RateSchedule:
    """Says at which ticks a fixed-rate event (feedback frame, IMU frame) is due.

    With ``first_ns`` the events sit on the grid ``first_ns + k * period``; without it the
    first call is due and sets the grid (for events switched on at an arbitrary time). If
    the caller falls more than a period behind, the grid restarts instead of bursting.
    """

    def __init__(self, rate_hz: float, first_ns: int | None = None):
        """Create the schedule; ``rate_hz`` > 0 [Hz], ``first_ns`` the first event [ns]."""
        self.period_ns = max(1, round(_NS_PER_S / rate_hz))
        self.next_ns = first_ns

    def due(self, now_ns: int) -> bool:
        """Return whether an event is due at ``now_ns`` [ns], and if so book it."""
        if self.next_ns is not None and now_ns < self.next_ns:
            return False
        if self.next_ns is None or self.next_ns + self.period_ns <= now_ns:
            self.next_ns = now_ns + self.period_ns
        else:
            self.next_ns += self.period_ns
        return True
