"""Barrel heat: a local estimate of the referee's heat, and how many shots it still allows.

The referee adds a fixed heat per projectile (10 for 17 mm, 100 for 42 mm), removes a tenth
of the cooling value every 100 ms, and punishes a barrel that goes past its limit (from
2025 on the launcher locks until the heat is back to 0). Its reports come ~100-200 ms
late, so the shooter keeps its own estimate: each shot it fires counts at once, the
referee's heat (0x0202) resets the estimate to the referee's value plus the shots the
referee has not reported yet (0x0207 after each projectile), and a margin under the limit
covers what is still in flight. docs/PROTOCOLS.md §6.5. Time comes from the caller's dt,
so a replay or the simulator behaves the same.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rm_base.control.validation import require_non_negative, require_positive
from rm_base.errors import ConfigError, InputRejectedError

#: The referee applies cooling in steps of this period [s].
COOLING_PERIOD_S = 0.1
HEAT_PER_17MM_SHOT = 10.0
HEAT_PER_42MM_SHOT = 100.0


@dataclass(frozen=True, slots=True)
class BarrelHeatParams:
    """How the shooter keeps under the heat limit.

    Attributes:
        heat_per_shot: heat one projectile adds (10 for 17 mm, 100 for 42 mm), > 0.
        margin: heat kept free under the limit for shots the referee has not counted yet
            and its report latency, >= 0 (e.g. the shots of 0.2 s at the highest rate).
        fallback_limit: the heat limit while the referee is silent or before it spoke,
            > 0: a conservative value (the lowest limit of the robot's levels), never none.
        fallback_cooling_per_s: the cooling assumed then, >= 0.
        confirm_timeout_s: a shot the referee has not reported within this is no longer
            added on top of its heat reports [s], > 0.
        steady_headroom: with fewer shots than this left under the limit, fire no faster
            than cooling sustains, >= 1. 1 (the default): the whole headroom at the asked
            rate, then each shot as cooling frees it (which is the rate cooling sustains);
            more smooths the change from one to the other.
    """

    heat_per_shot: float
    margin: float
    fallback_limit: float
    fallback_cooling_per_s: float
    confirm_timeout_s: float = 0.5
    steady_headroom: float = 1.0

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ('heat_per_shot', 'fallback_limit', 'confirm_timeout_s'):
            require_positive(owner, name, getattr(self, name))
        for name in ('margin', 'fallback_cooling_per_s'):
            require_non_negative(owner, name, getattr(self, name))
        if require_positive(owner, 'steady_headroom', self.steady_headroom) < 1.0:
            raise ConfigError(f'{owner}.steady_headroom must be >= 1 shot')


class BarrelHeat:
    """The heat estimate of one barrel (see the module docstring).

    Attributes:
        heat: the current estimate.
        limit, cooling_per_s: what the referee last set (0x0201), or the fallbacks.
    """

    def __init__(self, params: BarrelHeatParams) -> None:
        self.params = params
        self.heat = 0.0
        self.limit = params.fallback_limit
        self.cooling_per_s = params.fallback_cooling_per_s
        self._cooling_phase_s = 0.0
        self._unconfirmed: list[float] = []  # ages [s] of shots the referee has not reported

    def set_limits(self, heat_limit: float, cooling_per_s: float) -> None:
        """The referee's limit and cooling value (0x0201)."""
        _require_finite('heat_limit', heat_limit)
        _require_finite('cooling_per_s', cooling_per_s)
        self.limit = max(0.0, heat_limit)
        self.cooling_per_s = max(0.0, cooling_per_s)

    def use_fallback(self) -> None:
        """The referee went silent: back to the configured conservative limits."""
        self.limit = self.params.fallback_limit
        self.cooling_per_s = self.params.fallback_cooling_per_s

    def step(self, dt: float) -> None:
        """Let dt [s] pass: cooling in the referee's 100 ms steps, shots age."""
        if not dt > 0.0 or math.isinf(dt):
            raise InputRejectedError(f'dt must be finite and > 0, got {dt!r}')
        self._cooling_phase_s += dt
        steps = math.floor(self._cooling_phase_s / COOLING_PERIOD_S + 1e-9)
        if steps:
            self._cooling_phase_s -= steps * COOLING_PERIOD_S
            cooled = self.heat - steps * self.cooling_per_s * COOLING_PERIOD_S
            self.heat = max(0.0, cooled)
        timeout = self.params.confirm_timeout_s
        self._unconfirmed = [age + dt for age in self._unconfirmed if age + dt < timeout]

    def fired(self) -> None:
        """The shooter launched a projectile: it counts at once."""
        self.heat += self.params.heat_per_shot
        self._unconfirmed.append(0.0)

    def referee_shot(self) -> None:
        """The referee reported a projectile (0x0207): one of ours, or one we missed."""
        if self._unconfirmed:
            self._unconfirmed.pop(0)
        else:
            self.heat += self.params.heat_per_shot

    def referee_heat(self, heat: float) -> None:
        """The referee's heat (0x0202), plus our shots it has not reported yet."""
        _require_finite('heat', heat)
        self.heat = max(0.0, heat) + len(self._unconfirmed) * self.params.heat_per_shot

    def shots_allowed(self) -> int:
        """How many more shots keep the heat at or under limit - margin."""
        headroom = self.limit - self.params.margin - self.heat
        return max(0, math.floor(headroom / self.params.heat_per_shot + 1e-9))

    @property
    def sustainable_hz(self) -> float:
        """The firing rate cooling removes as fast as shots add [shots/s]."""
        return self.cooling_per_s / self.params.heat_per_shot

    def rate_limit(self, requested_hz: float) -> float:
        """The rate to fire at now: 0 without headroom, what cooling sustains near the limit."""
        shots = self.shots_allowed()
        if shots < 1:
            return 0.0
        if shots < self.params.steady_headroom:
            return min(requested_hz, self.sustainable_hz)
        return requested_hz


def _require_finite(name: str, value: float) -> None:
    if not math.isfinite(value):
        raise InputRejectedError(f'{name} must be finite, got {value!r}')
