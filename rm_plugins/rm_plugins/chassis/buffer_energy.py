"""Chassis power with the referee's buffer energy: spend it above a reserve, refill below.

The referee lets the chassis draw more than its power limit for a while: the excess comes
out of a buffer of at most 60 J, and below the limit the buffer refills at the same rate.
An empty buffer is punished (HP until 2024, the chassis cut for 5 s from 2025). So the
chassis may ask for the limit plus a share of what the buffer holds above a reserve, and
asks for less than the limit while the buffer is under the reserve, so it refills
(rm_control's power limit does the same: limit + gain x (buffer - setpoint)).
docs/PROTOCOLS.md §6.5.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rm_base.control.validation import require_non_negative
from rm_base.errors import InputRejectedError


@dataclass(frozen=True, slots=True)
class BufferEnergyParams:
    """How the chassis uses the buffer.

    Attributes:
        reserve_j: buffer energy to keep [J], >= 0 (above it spent, below it refilled).
        gain_w_per_j: extra power per joule above the reserve (less below it) [W/J], >= 0.
        max_boost_w: at most this above the referee's limit [W], >= 0.
    """

    reserve_j: float = 20.0
    gain_w_per_j: float = 2.0
    max_boost_w: float = 60.0

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ('reserve_j', 'gain_w_per_j', 'max_boost_w'):
            require_non_negative(owner, name, getattr(self, name))


def power_budget(limit_w: float, buffer_j: float, params: BufferEnergyParams) -> float:
    """The power to allow now [W]: limit + gain x (buffer - reserve), within [0, limit + boost].

    Raises:
        InputRejectedError: a NaN or infinite limit or buffer, or a negative limit.
    """
    if not (math.isfinite(limit_w) and math.isfinite(buffer_j)) or limit_w < 0.0:
        raise InputRejectedError(f'power limit {limit_w!r} W or buffer {buffer_j!r} J invalid')
    budget = limit_w + params.gain_w_per_j * (buffer_j - params.reserve_j)
    return min(max(budget, 0.0), limit_w + params.max_boost_w)
