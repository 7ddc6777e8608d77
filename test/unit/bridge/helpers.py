"""Helpers of the bridge unit tests."""

import itertools
import os

_names = itertools.count()


def unique_name() -> str:
    """A simulator channel name no other test uses."""
    return f'rm-bridge-unit-{os.getpid()}-{next(_names)}'
