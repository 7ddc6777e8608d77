"""argparse value types shared by the verbs (ros2cli's positive_float, nonnegative_int...)."""

from __future__ import annotations

import argparse
import math

#: Bounds of a rate or a duration [Hz or s]: a wait of 1e9 s (31 years) still fits the
#: clocks (time_t, a Duration's int64 ns), where `--keep-alive inf` or `-r 1e-300` raised.
LARGEST = 1e9
SMALLEST = 1.0 / LARGEST


def finite_float(text: str) -> float:
    """A float of either sign, up to LARGEST (targets, gains)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'{text} is not a finite number')
    if abs(value) > LARGEST:
        raise argparse.ArgumentTypeError(f'{text} is beyond {LARGEST:g}')
    return value


def positive_float(text: str) -> float:
    """A float > 0 (rates, durations), within [SMALLEST, LARGEST]."""
    value = finite_float(text)
    if not value > 0.0:
        raise argparse.ArgumentTypeError(f'{text} is not positive')
    if value < SMALLEST:
        raise argparse.ArgumentTypeError(f'{text} is below {SMALLEST:g}')
    return value


def nonnegative_float(text: str) -> float:
    """A float >= 0 (offsets, delays), up to LARGEST."""
    value = finite_float(text)
    if not value >= 0.0:
        raise argparse.ArgumentTypeError(f'{text} is negative')
    return value


def nonnegative_int(text: str) -> int:
    """An int >= 0 (counts)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not an integer') from None
    if value < 0:
        raise argparse.ArgumentTypeError(f'{text} is negative')
    return value


def positive_int(text: str) -> int:
    """An int > 0 (window sizes)."""
    value = nonnegative_int(text)
    if value == 0:
        raise argparse.ArgumentTypeError('0 is not positive')
    return value
