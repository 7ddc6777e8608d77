"""Faults that can be injected into a simulated motor (tests, fault-injection services)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum
from typing import Any

from rm_base.sim_devices.errors import SimConfigError


class FaultKind(Enum):
    """What goes wrong; the value is the name a service or config uses."""

    OFFLINE = 'offline'  # the motor neither receives nor sends (unplugged CAN / power)
    JAM = 'jam'  # locked rotor, or extra friction of a given torque
    OVER_TEMPERATURE = 'over_temperature'  # winding temperature forced to a value
    GARBAGE = 'garbage'  # random frames on the motor's feedback id or on random ids


@dataclass(frozen=True)
class Fault:
    """One injected fault and its parameters.

    Build one with the class methods (``Fault.jam(2.0)``) or :meth:`from_config`.

    Attributes:
        kind: what goes wrong.
        load_torque: JAM only: extra Coulomb friction at the output [N·m]; None locks the
            rotor completely.
        temperature: OVER_TEMPERATURE only: forced winding temperature [°C].
        rate_hz: GARBAGE only: frames per second, at most the world's tick rate.
        random_ids: GARBAGE only: random 11-bit ids instead of the motor's feedback id.
        can_id: GARBAGE only: send on this 11-bit id instead (a rogue node on, e.g., a
            command id); wins over ``random_ids``.
    """

    kind: FaultKind
    load_torque: float | None = None
    temperature: float = 130.0
    rate_hz: float = 100.0
    random_ids: bool = False
    can_id: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.kind, FaultKind):
            raise SimConfigError(f'fault kind must be a FaultKind, got {self.kind!r}')
        if self.load_torque is not None and not (
            math.isfinite(self.load_torque) and self.load_torque >= 0.0
        ):
            raise SimConfigError(f'jam load_torque must be >= 0 N·m, got {self.load_torque}')
        if not math.isfinite(self.temperature) or not -40.0 <= self.temperature <= 255.0:
            raise SimConfigError(f'fault temperature must be -40..255 °C, got {self.temperature}')
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0.0):
            raise SimConfigError(f'garbage rate_hz must be > 0, got {self.rate_hz}')
        if self.can_id is not None and (
            isinstance(self.can_id, bool)
            or not isinstance(self.can_id, int)
            or not 0 <= self.can_id <= 0x7FF
        ):
            raise SimConfigError(f'garbage can_id must be an int in 0..0x7FF, got {self.can_id!r}')

    @classmethod
    def offline(cls) -> Fault:
        """The motor stops receiving and answering."""
        return cls(FaultKind.OFFLINE)

    @classmethod
    def jam(cls, load_torque: float | None = None) -> Fault:
        """Lock the rotor (None) or add ``load_torque`` [N·m] of friction at the output."""
        return cls(FaultKind.JAM, load_torque=load_torque)

    @classmethod
    def over_temperature(cls, temperature: float = 130.0) -> Fault:
        """Force the winding temperature to ``temperature`` [°C]."""
        return cls(FaultKind.OVER_TEMPERATURE, temperature=temperature)

    @classmethod
    def garbage(
        cls, rate_hz: float = 100.0, random_ids: bool = False, can_id: int | None = None
    ) -> Fault:
        """Emit ``rate_hz`` frames/s of random bytes on the feedback id (or elsewhere)."""
        return cls(FaultKind.GARBAGE, rate_hz=rate_hz, random_ids=random_ids, can_id=can_id)

    @classmethod
    def from_config(cls, config: Mapping[str, Any]) -> Fault:
        """Build a fault from a plain dict, e.g. ``{'kind': 'jam', 'load_torque': 2.0}``.

        Raises:
            SimConfigError: unknown kind or key, or an invalid value.
        """
        params = dict(config)
        try:
            kind = FaultKind(params.pop('kind'))
        except KeyError:
            raise SimConfigError('a fault config needs a kind') from None
        except ValueError:
            known = sorted(k.value for k in FaultKind)
            raise SimConfigError(f'unknown fault kind {config["kind"]!r}; known: {known}') from None
        allowed = _PARAMS[kind]
        unknown = sorted(set(params) - allowed)
        if unknown:
            raise SimConfigError(
                f'{kind.value} fault takes {sorted(allowed) or "no parameters"}, got {unknown}'
            )
        try:
            return cls(kind, **params)
        except TypeError as err:
            raise SimConfigError(f'bad {kind.value} fault parameters: {err}') from err


_PARAMS: dict[FaultKind, frozenset[str]] = {
    FaultKind.OFFLINE: frozenset(),
    FaultKind.JAM: frozenset({'load_torque'}),
    FaultKind.OVER_TEMPERATURE: frozenset({'temperature'}),
    FaultKind.GARBAGE: frozenset({'rate_hz', 'random_ids', 'can_id'}),
}
