"""The bench's loop rates: ticks are divided by the window they were counted in.

The recorder of the scheduler starts after the robot's CPU snapshot and stops before the
next one; ticks divided by the longer snapshot window came out short of the loop's rate
(998.9 for a loop that skipped nothing).
"""

import pathlib
import time
from types import SimpleNamespace

import pytest
from support.bench import bench_module

ROOT = pathlib.Path(__file__).resolve().parents[2]


_bench = bench_module


class FakeScheduler:
    """What TickRecorder uses: ``observe_ticks`` and ``stats()``."""

    def __init__(self):
        self.ticks = 0
        self.observer = None

    def observe_ticks(self, observer):
        self.observer = observer

    def tick(self, now_ns):
        self.ticks += 1
        if self.observer is not None:
            self.observer(0, 1000)
        return 0

    def stats(self):
        return SimpleNamespace(ticks=self.ticks, skipped_ticks=0, overruns=0)


def test_a_loop_that_ticked_every_period_of_its_window_runs_at_its_rate():
    costs = _bench('robot_proc').loop_costs(
        # 1000 ticks in the loop's own 1.000 s; the CPU window around it was 1.011 s
        {'can-scheduler': (1000.0, 1000, 1.0)}, {'can-scheduler': 50.0}
    )['can-scheduler']
    assert costs['achieved_hz'] == pytest.approx(1000.0)
    assert costs['us_per_tick'] == pytest.approx(500.0)  # 50 % of a core at 1000 ticks/s
    assert costs['projected_pct'] == pytest.approx(50.0)


def test_a_loop_that_skipped_periods_shows_it_and_costs_more_per_tick():
    costs = _bench('robot_proc').loop_costs(
        {'plugin:chassis': (200.0, 190, 1.0)}, {'plugin:chassis': 19.0}
    )['plugin:chassis']
    assert costs['achieved_hz'] == pytest.approx(190.0)
    assert costs['us_per_tick'] == pytest.approx(1000.0)
    assert costs['projected_pct'] == pytest.approx(20.0)


def test_the_recorder_times_its_own_window():
    scheduler = FakeScheduler()
    recorder = _bench('scheduler_timing').TickRecorder(scheduler)
    recorder.start()
    for t in range(5):
        scheduler.tick(t)
    time.sleep(0.01)
    out = recorder.stop()
    assert out['ticks'] == 5
    assert 0.01 <= out['elapsed_s'] < 5.0
    assert out['achieved_hz'] == pytest.approx(5 / out['elapsed_s'])
    scheduler.tick(5)  # unhooked: no longer recorded
    assert len(recorder.ticks_ns) == len(recorder.errors_ns) == 5


def test_a_sleeper_launched_ahead_measures_from_its_start_time():
    # bench.canary is launched a second before the robot's window, so that a Python
    # process starting up does not load the machine inside it; its window starts at start.
    canary = _bench('canary')
    launched = time.monotonic()
    out = canary.run(0.05, start=time.time() + 0.2)
    assert time.monotonic() - launched >= 0.2 + 0.05 - 0.002  # the sleep before, then 50 ms
    assert out['ticks'] + out['skipped'] in range(48, 52)  # 50 periods of 1 ms, none before
