"""Fixtures for the simulator tests: stepped buses on private channel names."""

import pytest
from rm_base.sim import SimBus, SimWorld

from .helpers import unique_channel


@pytest.fixture
def make_bus():
    """Factory for stepped SimBus objects on fresh channels, all shut down afterwards."""
    buses = []

    def make(motors=(), **kwargs) -> SimBus:
        kwargs.setdefault('timing', 'stepped')
        bus = SimBus(kwargs.pop('channel', unique_channel()), motors=list(motors), **kwargs)
        buses.append(bus)
        return bus

    yield make
    for bus in buses:
        bus.shutdown()


@pytest.fixture
def make_world():
    """Factory for SimWorld.from_config with stepped timing, all closed afterwards."""
    worlds = []

    def make(config) -> SimWorld:
        world = SimWorld.from_config({'timing': 'stepped', **config})
        worlds.append(world)
        return world

    yield make
    for world in worlds:
        world.close()
