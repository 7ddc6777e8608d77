"""Reading single values of a simulated device's config dict, with errors naming the device."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, overload

from rm_base.hardware.protocols import mit
from rm_base.sim.devices import STD_ID_MAX
from rm_base.sim.errors import SimConfigError


@overload
def number(cfg: Mapping[str, Any], key: str, default: float, name: str) -> float: ...


@overload
def number(cfg: Mapping[str, Any], key: str, default: None, name: str) -> float | None: ...


def number(cfg: Mapping[str, Any], key: str, default: float | None, name: str) -> float | None:
    """``cfg[key]`` (or the default) as a float; None stays None.

    Raises:
        SimConfigError: not a finite number (a bool is not a number).
    """
    value = cfg.get(key, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SimConfigError(f'{name}: {key} must be a finite number, got {value!r}')
    return float(value)


def can_id(cfg: Mapping[str, Any], key: str, name: str, default: int | None = None) -> int:
    """``cfg[key]`` (or the default) as a standard CAN id (0..0x7FF)."""
    value = cfg.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= STD_ID_MAX:
        raise SimConfigError(f'{name}: {key} must be an int in 0..0x7FF, got {value!r}')
    return value


def flag(cfg: Mapping[str, Any], key: str, name: str) -> bool:
    """``cfg[key]`` as a bool, default False."""
    value = cfg.get(key, False)
    if not isinstance(value, bool):
        raise SimConfigError(f'{name}: {key} must be true or false, got {value!r}')
    return value


def mit_limits(cfg: Mapping[str, Any], base: mit.MitLimits, name: str) -> mit.MitLimits:
    """The MIT ranges of ``base`` with ``cfg['limits']`` (a mapping) applied."""
    overrides = cfg.get('limits')
    if overrides is not None and not isinstance(overrides, Mapping):
        raise SimConfigError(f'{name}: limits must be a mapping, got {overrides!r}')
    return base.with_overrides(dict(overrides) if overrides else None)
