"""PluginTask: a plugin in the loop, run at its own rate and at the next tick for a command."""

import threading
import time

import pytest
from rm_base.host.plugin_task import RESERVE_NS, PluginTask, TickInputs

MS = 1_000_000  # ns


class Time:
    def __init__(self, ns):
        self.nanoseconds = ns


class FakePlugin:
    """The part of PluginBase a task uses; records the time of each run."""

    def __init__(self, rate=100.0):
        self.name = 'fake'
        self.rate = rate
        self.joints = ()
        self.loop_reads = ()
        self.enabled = True
        self.command_listener = None
        self.runs = []
        self.disabled_for = None

    def run(self, now):
        self.runs.append(now.nanoseconds)

    def enable(self):
        self.enabled = True
        return True

    def disable(self, reason):
        self.enabled = False
        self.disabled_for = reason


def task_at(rate=100.0, refresh=None):
    clock = {'ns': 0}
    plugin = FakePlugin(rate)
    inputs = TickInputs(lambda: Time(clock['ns']), refresh)
    return plugin, PluginTask(plugin, inputs), clock


def run_ticks(task, clock, ticks):
    for i in range(ticks):
        clock['ns'] = i * MS
        task(i * MS, 0.001)


def test_a_100_hz_plugin_runs_on_every_tenth_tick_of_a_1_khz_loop():
    plugin, task, clock = task_at(100.0)
    run_ticks(task, clock, 100)
    assert plugin.runs == [i * 10 * MS for i in range(10)]
    assert (task.ticks, task.skipped, task.command_runs) == (10, 0, 0)


def test_when_a_command_arrives_expect_a_run_at_the_next_tick_then_the_rate_from_there():
    plugin, task, clock = task_at(100.0)
    run_ticks(task, clock, 3)  # ran at 0 ms; next due at 10 ms
    plugin.command_listener()  # a new command, between ticks
    for t in (3, 4, 13, 14):
        clock['ns'] = t * MS
        task(t * MS, 0.001)
    # at 3 ms for the command; the schedule goes on a period after that run (13 ms)
    assert plugin.runs == [0, 3 * MS, 13 * MS]
    assert task.command_runs == 1


def test_a_command_flood_runs_a_plugin_at_most_every_quarter_period():
    plugin, task, clock = task_at(100.0)  # 10 ms period: runs for commands >= 2 ms apart
    for t in range(10):
        plugin.command_listener()
        clock['ns'] = t * MS
        task(t * MS, 0.001)
    assert plugin.runs == [0, 2 * MS, 4 * MS, 6 * MS, 8 * MS]


def test_a_late_tick_skips_the_missed_deadlines_instead_of_catching_up():
    plugin, task, clock = task_at(100.0)
    for t in (0, 35, 36, 40):
        clock['ns'] = t * MS
        task(t * MS, 0.001)
    # due at 10, 20, 30 -> one run at 35 (10 and 20 skipped), then due at 40
    assert plugin.runs == [0, 35 * MS, 40 * MS]
    assert task.skipped == 2


def test_the_joint_view_is_refreshed_once_per_tick_and_only_when_a_plugin_runs():
    refreshed = []
    _, task, clock = task_at(100.0, refresh=refreshed.append)
    run_ticks(task, clock, 20)
    assert refreshed == [0, 10 * MS]


def test_when_the_lock_is_held_expect_the_loop_not_to_wait_and_to_run_later():
    plugin, task, _ = task_at(100.0)
    task.lock.acquire()
    try:
        assert task(0, 0.001) is False  # enable/disable in progress elsewhere
    finally:
        task.lock.release()
    assert task(MS, 0.001) is True
    assert plugin.runs == [0]  # TickInputs read the clock of the first run at 0 ns


def test_when_the_clock_fails_expect_the_plugin_disabled_with_the_reason():
    plugin = FakePlugin()

    def broken():
        raise RuntimeError('clock gone')

    task = PluginTask(plugin, TickInputs(broken))
    assert task(0, 0.001) is True
    assert plugin.disabled_for == 'loop failed: RuntimeError: clock gone'
    assert task.errors == 1
    assert task(MS, 0.001) is False  # disabled: not run again


def test_enable_and_disable_wait_for_a_run_in_progress():
    plugin, task, _ = task_at(100.0)
    inside, release = threading.Event(), threading.Event()

    def slow_run(now):
        inside.set()
        release.wait(5.0)

    plugin.run = slow_run
    loop = threading.Thread(target=task, args=(0, 0.001))
    loop.start()
    assert inside.wait(5.0)
    disabler = threading.Thread(target=task.disable, args=('test',))
    disabler.start()
    disabler.join(0.2)
    assert disabler.is_alive() and plugin.enabled  # waiting for the run
    release.set()
    disabler.join(5.0)
    loop.join(5.0)
    assert not plugin.enabled


def test_a_phase_moves_the_schedule_not_the_rate():
    clock = {'ns': 0}
    plugin = FakePlugin(100.0)
    task = PluginTask(plugin, TickInputs(lambda: Time(clock['ns'])), phase_ns=3 * MS)
    run_ticks(task, clock, 30)
    assert plugin.runs == [3 * MS, 13 * MS, 23 * MS]


TASK_CLOCK = {'ns': 0}  # [ns] the task's clock while ``task_clock`` holds


class SlowPlugin(FakePlugin):
    """A plugin whose run takes 300 us of the task's clock, so the task learns its cost.

    The clock (time.perf_counter_ns, which the task reads around a run) is the test's own
    while the fixture ``task_clock`` holds: on a loaded machine a busy-wait of real time
    was sometimes preempted for milliseconds, and the learned cost with it.
    """

    def run(self, now):
        super().run(now)
        TASK_CLOCK['ns'] += 300_000


@pytest.fixture
def task_clock(monkeypatch):
    TASK_CLOCK['ns'] = 1_000_000_000
    monkeypatch.setattr(time, 'perf_counter_ns', lambda: TASK_CLOCK['ns'])


def test_a_run_that_would_pass_the_deadline_waits_one_tick_then_runs_whatever_is_left(task_clock):
    left = {'ns': None}
    plugin = SlowPlugin(1000.0)
    inputs = TickInputs(lambda: Time(len(plugin.runs)), time_left=lambda: left['ns'])
    task = PluginTask(plugin, inputs)

    def tick(i):
        return task(i * MS, 0.001)

    assert tick(0) is True  # no deadline (a stepped loop): runs, learns its cost
    assert task.cost_ns > 100_000  # learned from the test's clock (a real run is microseconds)
    left['ns'] = RESERVE_NS + task.cost_ns // 2  # not enough left for a typical run
    assert tick(1) is False
    assert (task.deferred, task.ticks) == (1, 1)
    assert tick(2) is True  # at most one tick late, even if still short
    assert tick(3) is False and task.deferred == 2
    left['ns'] = RESERVE_NS + 10 * task.cost_ns  # room again: on time
    assert tick(4) is True and tick(5) is True
    # a 1 kHz plugin moved by a tick has run once for two of its deadlines
    assert (task.ticks, task.deferred, task.skipped) == (4, 2, 2)


def test_a_run_for_a_new_command_that_would_not_fit_waits_one_tick_too(task_clock):
    plugin = SlowPlugin(100.0)
    inputs = TickInputs(lambda: Time(len(plugin.runs)), time_left=lambda: 0)  # no time left
    task = PluginTask(plugin, inputs)
    assert task(0, 0.001) is False  # its scheduled run waits a tick...
    assert task(MS, 0.001) is True  # ...then runs
    plugin.command_listener()  # a command arrives
    assert task(2 * MS, 0.001) is False  # too soon after the last run (a quarter period)
    assert task(4 * MS, 0.001) is False and task.deferred == 2  # would pass the deadline
    assert task(5 * MS, 0.001) is True and task.command_runs == 1  # the next tick, surely
