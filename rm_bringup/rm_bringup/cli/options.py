"""argparse value types shared by the verbs (ros2cli's positive_float, nonnegative_int...)."""

from __future__ import annotations

import argparse


def positive_float(text: str) -> float:
    """A float > 0 (rates, durations)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not value > 0.0:
        raise argparse.ArgumentTypeError(f'{text} is not positive')
    return value


def nonnegative_float(text: str) -> float:
    """A float >= 0 (offsets, delays)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
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
