"""A simulated joint: a motor's output seen through a direction and a zero.

Also the config helpers of the simulated robot's parts (rm_base.sim.body,
rm_base.sim.launcher).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rm_base.config_schema import REQUIRED, check_table, number, read_value
from rm_base.sim.devices import SimDevice
from rm_base.sim.errors import SimConfigError


@dataclass(frozen=True)
class Joint:
    """A joint driven by one motor (gimbal yaw and pitch, the trigger, a friction wheel).

    Attributes:
        device: the motor.
        direction: +1 or -1, joint angle sign relative to the motor's output angle.
        zero: motor output angle at which the joint reads 0 [rad].
    """

    device: SimDevice
    direction: float = 1.0
    zero: float = 0.0

    @property
    def angle(self) -> float:
        """Joint angle [rad]."""
        return self.direction * (self.device.model.angle - self.zero)

    @property
    def velocity(self) -> float:
        """Joint velocity [rad/s]."""
        return self.direction * self.device.model.velocity


def config_number(
    cfg: Mapping[str, Any], key: str, owner: str, default: float | None = None
) -> float:
    """``cfg[key]`` (or default) as a finite float; SimConfigError naming ``owner.key``."""
    value: float = read_value(
        owner, number(key, REQUIRED if default is None else default, description=key), cfg,
        SimConfigError,
    )
    return value


def check_keys(cfg: Any, allowed: set[str] | frozenset[str], owner: str) -> None:
    """SimConfigError unless cfg is a mapping with only allowed keys."""
    check_table(owner, cfg, allowed, SimConfigError)


def motor_from_config(devices: Mapping[str, SimDevice], name: Any, owner: str) -> SimDevice:
    """The configured motor of that name."""
    if name not in devices:
        raise SimConfigError(f'{owner} names motor {name!r}, which is not configured')
    return devices[name]


def direction_from_config(value: Any, owner: str) -> float:
    """A joint or wheel direction: 1 or -1."""
    if value not in (1, -1) or isinstance(value, bool):
        raise SimConfigError(f'{owner}.direction must be 1 or -1, got {value!r}')
    return float(value)


def joint_from_config(
    cfg: Any,
    devices: Mapping[str, SimDevice],
    owner: str,
    extra: frozenset[str] | set[str] = frozenset(),
) -> Joint:
    """A joint from ``{motor, direction (1), zero (0.0)}`` plus the caller's extra keys."""
    check_keys(cfg, {'motor', 'direction', 'zero'} | extra, owner)
    return Joint(
        motor_from_config(devices, cfg.get('motor'), owner),
        direction_from_config(cfg.get('direction', 1), owner),
        config_number(cfg, 'zero', owner, 0.0),
    )
