"""Fixtures of the hardware-layer tests."""

import pytest

from .helpers import FakeClock, unique_channel


@pytest.fixture
def clock():
    return FakeClock()


@pytest.fixture
def channel():
    return unique_channel()
