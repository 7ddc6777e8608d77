"""Replays shared by the tests of a session: each scenario is replayed once (``replayed``).

Every replay also writes its output bag (commands, robot outputs, sim body) under the
session's temporary folder; a failing test's message names it, for ``rmcli bag plot``.
"""

from __future__ import annotations

import pytest

from replay.harness import ReplayResult, replay
from replay.scenarios import SCENARIOS


@pytest.fixture(scope='session')
def replayed(tmp_path_factory):
    """replayed(name) -> the ReplayResult of that scenario, replayed once per session."""
    cache: dict[str, ReplayResult] = {}

    def get(name: str) -> ReplayResult:
        if name not in cache:
            folder = tmp_path_factory.mktemp(f'replay_{name}')
            cache[name] = replay(SCENARIOS[name], output=folder / 'output')
            print(cache[name].summary(), f'-> {cache[name].output}')
        return cache[name]

    return get
