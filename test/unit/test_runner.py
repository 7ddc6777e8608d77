"""PluginRunner without ROS: runs at once for a new command, never closer than its gap."""

import itertools
import threading
import time

import pytest
from rm_base.host.runner import PluginRunner


class FakePlugin:
    """What the runner uses of a PluginBase: rate, name, enabled, run, listener."""

    def __init__(self, rate):
        self.rate = rate
        self.name = 'fake'
        self.enabled = True
        self.command_listener = None
        self.runs = []  # (perf_counter_ns, dt)

    def run(self, now, dt):
        self.runs.append((time.perf_counter_ns(), dt))


@pytest.fixture
def running():
    made = []

    def start(rate):
        plugin = FakePlugin(rate)
        runner = PluginRunner(plugin, time.monotonic)
        runner.start()
        made.append(runner)
        return plugin, runner

    yield start
    for runner in made:
        assert runner.stop()


@pytest.mark.parametrize(('rate', 'gap_ms'), [(200.0, 1.25), (20.0, 2.0)])
def test_when_commands_flood_expect_runs_never_closer_than_the_gap(running, rate, gap_ms):
    plugin, runner = running(rate)
    stop = threading.Event()

    def flood():  # a new command every ~0.1 ms
        while not stop.is_set():
            plugin.command_listener()
            time.sleep(0.0001)

    thread = threading.Thread(target=flood, daemon=True)
    thread.start()
    time.sleep(0.5)
    stop.set()
    thread.join()
    stamps = [t for t, _ in plugin.runs]
    gaps_ms = [(b - a) / 1e6 for a, b in itertools.pairwise(stamps)]
    print(f'{rate:g} Hz under a flood: {len(stamps)} runs in 0.5 s, '
          f'{runner.extra_runs} extra; shortest gap {min(gaps_ms):.3f} ms')
    assert runner.extra_runs > 0
    # sleeps only ever overshoot: no gap below the floor, whatever the load
    assert min(gaps_ms) >= gap_ms
    assert min(dt for _, dt in plugin.runs[1:]) >= gap_ms / 1e3


def test_when_a_command_arrives_expect_one_run_at_once_then_the_schedule_from_there(running):
    plugin, runner = running(2.0)  # 500 ms period
    assert _wait(lambda: len(plugin.runs) == 1)
    time.sleep(0.1)
    woken = time.perf_counter_ns()
    plugin.command_listener()
    assert _wait(lambda: len(plugin.runs) == 2)
    assert runner.extra_runs == 1
    assert (plugin.runs[1][0] - woken) / 1e6 < 100.0  # [ms]; the deadline was 400 ms away
    # the next scheduled run is a period after the extra one, not at the old deadline
    assert _wait(lambda: len(plugin.runs) == 3)
    assert (plugin.runs[2][0] - plugin.runs[1][0]) / 1e6 >= 500.0


def _wait(predicate, timeout=10.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.001)
    return predicate()
