"""Checks shared by the control config dataclasses (construction time, not the hot path)."""

import math
from numbers import Real

from rm_base.errors import ConfigError


def require_real(owner: str, name: str, value: object) -> float:
    """Return value as a float, or raise ConfigError if it is not a real number (or NaN)."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ConfigError(f'{owner}.{name} must be a number, got {value!r}')
    number = float(value)
    if math.isnan(number):
        raise ConfigError(f'{owner}.{name} must not be NaN')
    return number


def require_non_negative(owner: str, name: str, value: object, *, finite: bool = True) -> float:
    """Return value as a float >= 0 (finite unless finite=False), else raise ConfigError."""
    number = require_real(owner, name, value)
    if number < 0.0 or (finite and math.isinf(number)):
        bound = 'finite and >= 0' if finite else '>= 0 (inf allowed)'
        raise ConfigError(f'{owner}.{name} must be {bound}, got {value!r}')
    return number


def require_positive(owner: str, name: str, value: object, *, finite: bool = True) -> float:
    """Return value as a float > 0 (finite unless finite=False), else raise ConfigError."""
    number = require_real(owner, name, value)
    if number <= 0.0 or (finite and math.isinf(number)):
        bound = 'finite and > 0' if finite else '> 0 (inf allowed)'
        raise ConfigError(f'{owner}.{name} must be {bound}, got {value!r}')
    return number
