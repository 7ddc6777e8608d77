"""Scheduler: update all, then pack all, then send; timing statistics; on_error; thread."""

import gc
import threading

import can
import pytest
from rm_base.loop import LoopConfigError
from rm_base.loop.data import JOINT_EFFORTS, JOINT_STATES, JOINT_TARGETS
from rm_base.loop.scheduler import Scheduler
from rm_base.loop.timing import HISTOGRAM_EDGES_US
from rm_base.runtime.realtime import in_loop_thread
from support.hardware import MS, T0
from support.ros import wait_until

# most tests here run the loop's thread in real time (the rest take milliseconds)
pytestmark = pytest.mark.realtime


class Recorder:
    def __init__(self, events, name, frame=True):
        self.events = events
        self.name = name
        self.frame = frame
        self.dts = []

    def update(self, now_ns, dt):
        self.events.append(('update', self.name, now_ns))
        self.dts.append(dt)

    def pack_command(self):
        self.events.append(('pack', self.name))
        if not self.frame:
            return None
        return can.Message(arbitration_id=len(self.name), data=self.name.encode())


def make(events, **kwargs):
    a, b = Recorder(events, 'a'), Recorder(events, 'bb')
    g = Recorder(events, 'ggg')
    silent = Recorder(events, 'none', frame=False)

    def sender(bus):
        return lambda msg: events.append(('send', bus, bytes(msg.data).decode()))

    packers = [
        (g, sender('can0')),
        (a, sender('can0')),
        (silent, sender('can0')),
        (b, sender('can1')),
    ]
    return Scheduler([a, b], packers, **kwargs), a


def test_tick_updates_all_then_packs_all_then_sends_all():
    events = []
    scheduler, _ = make(events)
    assert scheduler.tick(T0) == 3
    assert events == [
        ('update', 'a', T0),
        ('update', 'bb', T0),
        ('pack', 'ggg'),
        ('pack', 'a'),
        ('pack', 'none'),
        ('pack', 'bb'),
        ('send', 'can0', 'ggg'),
        ('send', 'can0', 'a'),
        ('send', 'can1', 'bb'),
    ]


def test_dt_is_the_time_since_the_previous_tick():
    events = []
    scheduler, a = make(events)
    scheduler.tick(T0)
    scheduler.tick(T0 + 2 * MS)
    scheduler.tick(T0 + 2 * MS)  # same time again: falls back to the nominal period
    assert a.dts == pytest.approx([0.001, 0.002, 0.001])
    assert scheduler.stats().ticks == 3


def test_rate_must_be_positive():
    with pytest.raises(LoopConfigError, match='rate must be > 0'):
        Scheduler([], [], rate_hz=0.0)


class SteppedClock:
    """A clock the scheduler thread advances through its sleep function."""

    def __init__(self, tick_cost_ns=0):
        self.now = T0
        self.tick_cost_ns = tick_cost_ns

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.now += int(seconds * 1e9)


def test_thread_sleeps_to_absolute_deadlines_runs_late_ticks_at_once_and_counts_overruns():
    clock = SteppedClock()
    starts = []

    class Slow:
        def update(self, now_ns, dt):
            starts.append((now_ns - T0) / MS)
            if len(starts) in (4, 5):
                clock.now += 2_500_000  # 2.5 ms of work at 1 kHz

        def pack_command(self):
            return None

    scheduler = Scheduler([Slow()], [], rate_hz=1000.0, clock_ns=clock, sleep=clock.sleep)

    def stop_after_ten():
        if len(starts) >= 10:
            scheduler.stop(timeout_s=0.0)

    scheduler.add_after_tick(stop_after_ten)
    scheduler.start()
    assert wait_until(lambda: not scheduler.running, timeout=10.0)
    # 4th tick at 3 ms ends at 5.5 ms: the 4 ms period passed whole (skipped), the 5 ms
    # one has not: its tick runs at once, 0.5 ms late, and ends at 8 ms; the 6 and 7 ms
    # periods are skipped, the 8 ms tick starts on time. No burst to catch up.
    assert starts == [0, 1, 2, 3, 5.5, 8, 9, 10, 11, 12]
    stats = scheduler.stats()
    assert stats.overruns == 2
    assert stats.skipped_ticks == 3
    assert stats.max_tick_us == pytest.approx(2500.0)
    assert stats.max_error_us == pytest.approx(500.0)  # the late tick
    assert stats.histogram[0] == stats.ticks - 1 == 9
    assert len(stats.histogram) == len(HISTOGRAM_EDGES_US) + 1


def test_an_observer_gets_each_ticks_start_error_and_duration():
    clock = SteppedClock()
    seen = []

    class Work:
        def update(self, now_ns, dt):
            clock.now += 300_000  # 0.3 ms of work

        def pack_command(self):
            return None

    scheduler = Scheduler([Work()], [], rate_hz=1000.0, clock_ns=clock, sleep=clock.sleep)

    def observe(error_ns, tick_ns):
        seen.append((error_ns, tick_ns))
        if len(seen) == 3:
            scheduler.stop(timeout_s=0.0)

    scheduler.observe_ticks(observe)
    scheduler.start()
    assert wait_until(lambda: not scheduler.running, timeout=10.0)
    assert seen == [(0, 300_000)] * 3
    scheduler.observe_ticks(None)
    scheduler.tick(T0)  # stepped ticks are not the thread's: never observed
    assert len(seen) == 3


def test_on_error_decides_whether_to_go_on():
    clock = SteppedClock()
    failures = []

    class Failing:
        def update(self, now_ns, dt):
            raise RuntimeError('boom')

        def pack_command(self):
            return None

    def on_error(exc):
        failures.append(exc)
        return len(failures) < 3

    final = threading.Event()
    scheduler = Scheduler([Failing()], [], on_error=on_error, clock_ns=clock, sleep=clock.sleep)
    scheduler.start(final=final.set)
    assert wait_until(final.is_set, timeout=10.0)
    assert len(failures) == 3
    assert scheduler.stats().errors == 3
    assert not scheduler.running


def test_without_on_error_the_loop_stops_at_the_first_exception():
    clock = SteppedClock()

    class Failing:
        def update(self, now_ns, dt):
            raise RuntimeError('boom')

        def pack_command(self):
            return None

    final = threading.Event()
    scheduler = Scheduler([Failing()], [], clock_ns=clock, sleep=clock.sleep)
    scheduler.start(final=final.set)
    assert wait_until(final.is_set, timeout=10.0)
    assert scheduler.stats().errors == 1


def test_real_thread_runs_and_stops_idempotently():
    events = []
    scheduler, _ = make(events, rate_hz=1000.0)
    scheduler.start()
    scheduler.start()  # idempotent while running
    assert wait_until(lambda: scheduler.stats().ticks >= 20, timeout=10.0)
    scheduler.stop()
    scheduler.stop()
    assert not scheduler.running
    ticks = scheduler.stats().ticks
    assert scheduler.stats().ticks == ticks  # stopped means stopped


class Stage:
    def __init__(self, events, name, works=True, reads=(), writes=()):
        self.events = events
        self.name = name
        self.works = works
        self.reads, self.writes = reads, writes

    def __call__(self, now_ns, dt):
        self.events.append(('stage', self.name, now_ns))
        return self.works


def test_the_order_follows_what_each_stage_reads_and_writes_not_the_order_added():
    events = []
    scheduler, _ = make(events)
    power = Stage(events, 'power limit', reads=(JOINT_EFFORTS,), writes=(JOINT_EFFORTS,))
    plugin = Stage(events, 'plugin chassis', reads=(JOINT_STATES,), writes=(JOINT_TARGETS,))
    scheduler.add_stage(power)
    scheduler.add_stage(plugin)
    scheduler.add_stage(Stage(events, 'feedback', writes=(JOINT_STATES,)))
    assert scheduler.order() == (
        'feedback', 'plugin chassis', 'actuators', 'power limit', 'pack', 'send'
    )
    scheduler.tick(T0)
    order = [e[:2] for e in events if e[0] in ('stage', 'update')] + [events[-1][:1]]
    assert order == [
        ('stage', 'feedback'),
        ('stage', 'plugin chassis'),
        ('update', 'a'),
        ('update', 'bb'),
        ('stage', 'power limit'),
        ('send',),
    ]
    # the output stage runs before anything is packed
    assert events.index(('stage', 'power limit', T0)) < events.index(('pack', 'ggg'))


def test_every_component_is_timed_and_an_idle_stage_is_not_counted():
    events = []
    scheduler, _ = make(events)
    scheduler.add_stage(Stage(events, 'plugin busy'))
    scheduler.add_stage(Stage(events, 'plugin idle', works=False))
    for i in range(3):
        scheduler.tick(T0 + i * MS)
    counts = {name: s.count for name, s in scheduler.component_stats()}
    assert counts == {
        'plugin busy': 3, 'plugin idle': 0, 'actuators': 3, 'pack': 3, 'send': 3, 'gc': 0,
    }  # a stepped tick leaves garbage collection to the interpreter
    assert [name for name, _ in scheduler.stats().components] == list(counts)


def test_a_removed_stage_no_longer_runs_and_a_name_cannot_be_taken_twice():
    events = []
    scheduler, _ = make(events)
    scheduler.add_stage(Stage(events, 'plugin x'))
    with pytest.raises(LoopConfigError, match="component named 'plugin x' already"):
        scheduler.add_stage(Stage(events, 'plugin x'))
    assert scheduler.remove_stage('plugin x')
    assert not scheduler.remove_stage('plugin x')
    scheduler.tick(T0)
    assert not [e for e in events if e[0] == 'stage']
    scheduler.add_stage(Stage(events, 'plugin x'))  # the name is free again


def test_priority_is_asked_for_on_the_loop_thread_and_a_refusal_is_a_warning(caplog):
    asked = []

    def refuse(priority):
        asked.append((priority, threading.current_thread().name))
        raise PermissionError(1, 'Operation not permitted')

    scheduler = Scheduler([], [], priority=50, set_priority=refuse, thread_name='loop-test')
    with caplog.at_level('WARNING', logger='rm_base.loop.scheduler'):
        scheduler.start()
        assert wait_until(lambda: scheduler.stats().ticks >= 5, timeout=10.0)  # runs on
        scheduler.stop()
    assert asked == [(50, 'loop-test')]
    assert 'without real-time priority (SCHED_FIFO 50' in caplog.text


def test_priority_zero_keeps_normal_scheduling():
    asked = []
    scheduler = Scheduler([], [], priority=0, set_priority=asked.append)
    scheduler.start()
    assert wait_until(lambda: scheduler.stats().ticks >= 5, timeout=10.0)
    scheduler.stop()
    assert asked == []


@pytest.mark.parametrize('priority', [-1, 100])
def test_priority_outside_0_to_99_is_refused(priority):
    with pytest.raises(LoopConfigError, match='priority must be 0-99'):
        Scheduler([], [], priority=priority)


def test_after_tick_callbacks_run_once_per_tick_after_the_frames_went_out():
    events = []
    scheduler, _ = make(events)
    scheduler.add_after_tick(lambda: events.append(('after',)))
    for i in range(2):
        events.clear()
        scheduler.tick(T0 + i * MS)
        assert events.count(('after',)) == 1
        assert events[-1] == ('after',) and events[-2][0] == 'send'
    callback = events.append
    scheduler.add_after_tick(callback)
    scheduler.remove_after_tick(callback)
    scheduler.tick(T0 + 2 * MS)
    assert events[-1] == ('after',)


def test_time_left_is_known_only_inside_a_tick_of_the_loop_thread():
    seen = []

    class Probe:
        name = 'probe'
        reads = writes = ()

        def __call__(self, now_ns, dt):
            seen.append(scheduler.time_left_ns())
            return True

    scheduler = Scheduler([], [], rate_hz=1000.0)
    scheduler.add_stage(Probe())
    scheduler.tick(T0)  # stepped: no deadline
    assert seen == [None]
    scheduler.start()
    assert wait_until(lambda: len(seen) >= 20, timeout=10.0)
    scheduler.stop()
    assert all(left is not None and left <= 1_000_000 for left in seen[1:])
    assert scheduler.time_left_ns() is None


def test_while_the_thread_runs_the_loop_collects_garbage_after_its_ticks():
    class Cycles:
        # each tick leaves reference cycles behind: only a collection frees them
        name = 'cycles'
        reads = writes = ()

        def __call__(self, now_ns, dt):
            for _ in range(200):
                a = []
                a.append(a)
            return True

    assert gc.isenabled()
    scheduler = Scheduler([], [], rate_hz=1000.0)
    scheduler.add_stage(Cycles())
    scheduler.start()
    assert wait_until(lambda: not gc.isenabled(), timeout=10.0)  # the loop's, not CPython's
    assert wait_until(lambda: dict(scheduler.component_stats())['gc'].count >= 3, timeout=10.0)
    scheduler.stop()
    assert gc.isenabled()  # given back


def test_a_loop_told_not_to_leaves_garbage_collection_to_the_interpreter():
    scheduler = Scheduler([], [], rate_hz=1000.0, collect_garbage=False)
    scheduler.start()
    assert wait_until(lambda: scheduler.stats().ticks >= 20, timeout=10.0)
    assert gc.isenabled()
    scheduler.stop()
    assert dict(scheduler.component_stats())['gc'].count == 0



class LoopMark:
    """A stage that records whether it runs in a thread marked as a control loop's."""

    name = 'mark'
    reads = writes = ()

    def __init__(self):
        self.marks = []

    def __call__(self, now_ns, dt):
        self.marks.append(in_loop_thread())
        return False


def test_the_loop_thread_is_marked_as_one_while_it_ticks_and_not_in_final():
    scheduler, _ = make([], rate_hz=1000.0)
    probe = LoopMark()
    scheduler.add_stage(probe)
    scheduler.tick(T0)  # a stepped tick runs in the caller's thread: not a loop's
    final = []
    scheduler.start(final=lambda: final.append(in_loop_thread()))
    assert wait_until(lambda: len(probe.marks) >= 5, timeout=10.0)
    scheduler.stop()
    assert probe.marks[0] is False and all(probe.marks[1:]) and final == [False]
    assert not in_loop_thread()
