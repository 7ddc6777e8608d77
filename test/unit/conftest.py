"""Fixtures of the unit tests: a fake monotonic clock and a private CAN channel."""

import pytest
from support.hardware import FakeClock, unique_channel


@pytest.fixture
def clock():
    return FakeClock()


@pytest.fixture
def channel():
    return unique_channel()
