"""ManagedBus: dispatch, reconnection with back-off, counters, load, logging, shutdown.

Why one module: every test exercises one class, ManagedBus, with the same fake buses.
"""

import logging
import threading
import time

import can
import pytest
from rm_base.hardware.bus import BusState, ManagedBus, frame_bits
from rm_base.hardware.config import BusConfig
from rm_base.hardware.errors import BusError, HardwareConfigError
from support.hardware import FakeClock
from support.ros import wait_until

TIMEOUT = 10.0  # [s] generous: condition waits only


def virtual(channel, **extra):
    return BusConfig.from_dict('vcan', {'interface': 'virtual', 'channel': channel, **extra})


def frame(can_id, data=b'\x01\x02'):
    return can.Message(arbitration_id=can_id, data=data, is_extended_id=False)


class FakeBus(can.BusABC):
    """A bus whose receive and send can be broken on demand."""

    def __init__(self, channel=None, **kwargs):
        super().__init__(channel=channel)
        self.kwargs = kwargs
        self.broken = threading.Event()
        self.fail_send = False
        self.sent = []
        self.closed = False

    def _recv_internal(self, timeout):
        if self.broken.wait(timeout):
            raise can.CanOperationError('adapter gone')
        return None, False

    def send(self, msg, timeout=None):
        if self.fail_send:
            raise can.CanOperationError('Transmit buffer full')
        self.sent.append(msg)

    def shutdown(self):
        self.closed = True
        super().shutdown()


class Factory:
    """Builds FakeBus objects; ``plan`` lists, per attempt, True (open) or False (fail)."""

    def __init__(self, plan=()):
        self.plan = list(plan)
        self.buses = []
        self.attempts = 0

    def __call__(self, **kwargs):
        self.attempts += 1
        if self.plan and not self.plan.pop(0):
            raise can.CanInitializationError('no such device')
        bus = FakeBus(**kwargs)
        self.buses.append(bus)
        return bus


def fake(**extra):
    cfg = {
        'interface': 'fake',
        'channel': 'x',
        'reconnect_initial_s': 0.01,
        'reconnect_max_s': 0.04,
        'receive_timeout_s': 0.01,
        **extra,
    }
    return BusConfig.from_dict('fake0', cfg)


# --- dispatch over a python-can virtual bus ---
def test_frames_are_dispatched_by_arbitration_id(channel):
    got = []
    with ManagedBus(virtual(channel)) as bus, can.Bus(interface='virtual', channel=channel) as peer:
        bus.add_handler(0x201, lambda msg, now: got.append(('a', msg.arbitration_id)) or True)
        bus.add_handler(0x201, lambda msg, now: False)  # shares the id, does not match
        bus.add_handler(0x205, lambda msg, now: got.append(('b', msg.arbitration_id)) or True)
        bus.start()
        for can_id in (0x201, 0x205, 0x300):
            peer.send(frame(can_id))
        assert wait_until(lambda: bus.stats().frames_received == 3, TIMEOUT)
        assert got == [('a', 0x201), ('b', 0x205)]
        assert bus.stats().frames_unmatched == 1
        assert bus.send(frame(0x200))
        assert peer.recv(TIMEOUT).arbitration_id == 0x200


def test_handler_exceptions_are_counted_and_do_not_stop_the_bus(channel):
    def broken(msg, now):
        raise RuntimeError('bug')

    with ManagedBus(virtual(channel)) as bus, can.Bus(interface='virtual', channel=channel) as peer:
        bus.add_handler(0x201, broken)
        bus.start()
        peer.send(frame(0x201))
        peer.send(frame(0x201))
        assert wait_until(lambda: bus.stats().handler_errors == 2, TIMEOUT)
        assert bus.state is BusState.UP


def test_bus_load_is_estimated_from_frame_bits(channel):
    clock = FakeClock()
    bus = ManagedBus(virtual(channel, bitrate=1_000_000), clock_ns=clock)
    with bus:
        bus.start()
        bus.stats()  # reset the load window
        for _ in range(1000):
            assert bus.send(frame(0x200, bytes(8)))
        clock.advance_ms(1000)
        stats = bus.stats()
    # 1000 standard 8-byte frames of 47 + 64 bits in 1 s
    assert frame_bits(frame(0x200, bytes(8))) == 111
    assert stats.load_bps == pytest.approx(111_000)
    assert stats.load_fraction == pytest.approx(0.111)
    assert stats.frames_sent == 1000


# --- arrival stamps ---
class QueuedBus(can.BusABC):
    """A bus whose receive returns the given frames, then nothing."""

    def __init__(self, frames, **kwargs):
        super().__init__(channel='queued')
        self.frames = list(frames)

    def _recv_internal(self, timeout):
        return (self.frames.pop(0), False) if self.frames else (None, False)

    def send(self, msg, timeout=None):
        pass


WALL = 1_000.0  # [s] the frame clock's "now" in the table below


@pytest.mark.parametrize(
    ('timestamp', 'stamped_ms_before_receipt', 'late'),
    [
        (WALL - 0.2, 200.0, 1),  # waited 200 ms in the queue: stamped at its arrival
        (WALL - 0.0005, 0.5, 0),  # 0.5 ms: backdated, not counted as late
        (WALL + 0.5, 0.0, 0),  # from the future: the interface's clock is its own
        (WALL - 10.0, 0.0, 0),  # older than MAX_FRAME_AGE_S: a clock of its own
        (0.0, 0.0, 0),  # no timestamp
    ],
)
def test_when_a_frame_waited_in_the_queue_expect_it_stamped_at_its_arrival(
    timestamp, stamped_ms_before_receipt, late
):
    clock = FakeClock()
    received = clock.now_ns
    msg = can.Message(arbitration_id=0x201, data=bytes(8), is_extended_id=False,
                      timestamp=timestamp)
    got = []
    bus = ManagedBus(fake(), clock_ns=clock, frame_clock=lambda: WALL,
                     bus_factory=lambda **kw: QueuedBus([msg]))
    bus.add_handler(0x201, lambda m, now_ns: got.append(now_ns) or True)
    with bus:
        bus.start()
        assert wait_until(lambda: got, TIMEOUT)
    assert received - got[0] == pytest.approx(stamped_ms_before_receipt * 1e6, abs=1e3)
    assert bus.stats().frames_late == late


def test_when_the_clock_is_injected_expect_frames_stamped_at_receipt():
    clock = FakeClock()
    msg = can.Message(arbitration_id=0x201, data=bytes(8), is_extended_id=False,
                      timestamp=1.0)
    got = []
    bus = ManagedBus(fake(), clock_ns=clock, bus_factory=lambda **kw: QueuedBus([msg]))
    bus.add_handler(0x201, lambda m, now_ns: got.append(now_ns) or True)
    with bus:
        bus.start()
        assert wait_until(lambda: got, TIMEOUT)
    assert got == [clock.now_ns]


def test_when_the_receive_thread_starts_late_expect_queued_frames_stamped_when_sent(channel):
    got = []
    with ManagedBus(virtual(channel)) as bus, can.Bus(interface='virtual', channel=channel) as peer:
        bus.add_handler(0x201, lambda m, now_ns: got.append(now_ns) or True)
        bus.open()  # joined the virtual bus, no receive thread yet: frames queue
        sent_ns = time.perf_counter_ns()
        peer.send(frame(0x201))
        time.sleep(0.3)
        bus.start()
        assert wait_until(lambda: got, TIMEOUT)
        received_ns = time.perf_counter_ns()
    # python-can's virtual bus stamps a frame (time.time()) when it is sent
    assert got[0] == pytest.approx(sent_ns, abs=50e6)
    assert received_ns - got[0] >= 250e6
    assert bus.stats().frames_late == 1


# --- errors and reconnection ---
def test_when_the_adapter_disappears_expect_reopen_with_exponential_backoff(caplog):
    factory = Factory(plan=[True, False, False, False, True])
    reopened, failed = [], []
    bus = ManagedBus(fake(), bus_factory=factory)
    bus.add_reopen_listener(reopened.append)
    bus.add_failure_listener(failed.append)
    caplog.set_level(logging.WARNING, logger='rm_base.hardware.bus')
    with bus:
        bus.start()
        assert bus.state is BusState.UP and bus.generation == 1
        factory.buses[0].broken.set()  # recv raises CanOperationError
        assert wait_until(lambda: bus.generation == 2, TIMEOUT)
        stats = bus.stats()
    assert factory.buses[0].closed
    assert stats.receive_errors == 1
    assert stats.open_failures == 3
    assert stats.reopen_count == 1
    assert 'adapter gone' in stats.last_error or 'no such device' in stats.last_error
    delays = [
        r.getMessage().split('reopening in ')[1]
        for r in caplog.records
        if 'reopening in' in r.getMessage()
    ]
    # first delay 10 ms, doubled on each failure, capped at 40 ms
    assert delays == ['0.010 s', '0.020 s', '0.040 s', '0.040 s']
    assert len(reopened) == 1
    assert len(failed) == 1  # failed opens while down are not new failures


class BrokenAtBirth(FakeBus):
    """Opens fine, fails at the first receive: a bus that is bus-off for good."""

    def _recv_internal(self, timeout):
        raise can.CanOperationError('bus off')


def reopen_delays(caplog):
    return [
        r.getMessage().split('reopening in ')[1]
        for r in caplog.records
        if 'reopening in' in r.getMessage()
    ]


def test_when_the_bus_fails_as_soon_as_it_is_open_expect_the_backoff_to_keep_growing(caplog):
    opened = []

    def factory(**kwargs):
        opened.append(BrokenAtBirth(**kwargs))
        return opened[-1]

    caplog.set_level(logging.WARNING, logger='rm_base.hardware.bus')
    bus = ManagedBus(fake(reconnect_max_s=0.5), bus_factory=factory)
    with bus:
        bus.start()
        assert wait_until(lambda: len(reopen_delays(caplog)) >= 5, TIMEOUT)
    # each reopen succeeds, and fails at once: the waits double up to the cap regardless
    assert reopen_delays(caplog)[:5] == ['0.010 s', '0.020 s', '0.040 s', '0.080 s', '0.160 s']


def test_when_the_bus_had_stayed_up_expect_the_backoff_to_start_over(caplog):
    factory = Factory(plan=[True, False, True])
    caplog.set_level(logging.WARNING, logger='rm_base.hardware.bus')
    with ManagedBus(fake(reconnect_max_s=0.1), bus_factory=factory) as bus:
        bus.start()
        factory.buses[0].broken.set()
        assert wait_until(lambda: bus.generation == 2, TIMEOUT)  # waited 10 ms, then 20
        time.sleep(0.2)  # up for longer than the longest wait: recovered
        factory.buses[1].broken.set()
        assert wait_until(lambda: bus.generation == 3, TIMEOUT)
    assert reopen_delays(caplog) == ['0.010 s', '0.020 s', '0.010 s']


def test_when_open_fails_at_start_expect_retries_in_the_background():
    factory = Factory(plan=[False, True])
    with ManagedBus(fake(), bus_factory=factory) as bus:
        bus.start()  # does not raise
        assert wait_until(lambda: bus.state is BusState.UP, TIMEOUT)
        assert bus.generation == 1  # the first successful open is not a "reopen"
        assert bus.stats().reopen_count == 0


def test_when_sends_keep_failing_expect_a_reopen():
    factory = Factory()
    with ManagedBus(fake(send_failures_to_reopen=5), bus_factory=factory) as bus:
        bus.start()
        factory.buses[0].fail_send = True
        for _ in range(5):
            assert not bus.send(frame(0x200))
        assert wait_until(lambda: bus.generation == 2, TIMEOUT)
        assert bus.send(frame(0x200))
        assert factory.buses[1].sent[-1].arbitration_id == 0x200
        assert bus.stats().send_errors == 5


def test_an_observer_sees_every_accepted_send_and_no_failed_one():
    factory = Factory()
    seen = []
    with ManagedBus(fake(), bus_factory=factory) as bus:
        bus.start()
        bus.observe_sent(lambda msgs: seen.append([m.arbitration_id for m in msgs]))
        assert bus.send(frame(0x200))
        assert bus.send_many([frame(0x1FF), frame(0x2FF)]) == 2
        factory.buses[0].fail_send = True
        assert not bus.send(frame(0x200))
        factory.buses[0].fail_send = False
        bus.observe_sent(None)
        assert bus.send(frame(0x200))
    assert seen == [[0x200], [0x1FF], [0x2FF]]


def test_send_while_down_returns_false_and_counts():
    factory = Factory(plan=[False] * 1000)
    with ManagedBus(fake(reconnect_initial_s=5.0, reconnect_max_s=5.0), bus_factory=factory) as bus:
        bus.start()
        assert bus.state is BusState.DOWN
        assert not bus.send(frame(0x200))
        assert bus.stats().send_errors == 1


def test_error_frames_are_counted():
    with ManagedBus(fake(), bus_factory=Factory()) as bus:
        err = can.Message(is_error_frame=True)
        assert bus.dispatch(err, 0) == 0
        assert bus.stats().error_frames == 1
        assert bus.stats().frames_received == 0
        # the kernel's bus-off, with the controller's counters (docs/PROTOCOLS.md §7)
        off = can.Message(is_error_frame=True, arbitration_id=0x240,
                          data=bytes([0, 0, 0, 0, 0, 0, 255, 0]))
        bus.dispatch(off, 0)
        stats = bus.stats()
        assert (stats.error_frames, stats.bus_off) == (2, 1)
        assert stats.last_error_frame == 'bus-off counters, counters tx 255 rx 0'


def test_bus_options_are_passed_to_python_can():
    factory = Factory()
    cfg = fake(bitrate=500_000, fd=True, data_bitrate=2_000_000, options={'serial': 'abc'})
    with ManagedBus(cfg, bus_factory=factory) as bus:
        bus.start()
    kwargs = factory.buses[0].kwargs
    assert kwargs == {
        'bitrate': 500_000,
        'fd': True,
        'data_bitrate': 2_000_000,
        'serial': 'abc',
        'interface': 'fake',
        'ignore_config': True,
    }


# --- shutdown and logging ---
def test_shutdown_is_idempotent_and_final():
    factory = Factory()
    bus = ManagedBus(fake(), bus_factory=factory)
    bus.start()
    bus.shutdown()
    bus.shutdown()
    assert bus.state is BusState.CLOSED
    assert factory.buses[0].closed
    assert not bus.send(frame(0x200))
    with pytest.raises(BusError, match='shut down'):
        bus.start()


@pytest.mark.parametrize('suffix', ['.asc', '.csv', '.log', '.blf'])
def test_frames_are_logged_with_python_can_writers(tmp_path, channel, suffix):
    path = tmp_path / f'can{suffix}'
    started = time.time()
    bus = ManagedBus(virtual(channel, log_file=str(path)))
    with bus, can.Bus(interface='virtual', channel=channel) as peer:
        bus.add_handler(0x205, lambda msg, now: True)
        bus.start()
        bus.send(frame(0x200, bytes.fromhex('03e8')))
        peer.send(frame(0x205, bytes.fromhex('1fff')))
        assert wait_until(lambda: bus.stats().frames_received == 1, TIMEOUT)
    with can.LogReader(str(path)) as reader:
        logged = sorted(reader, key=lambda m: m.arbitration_id)
    assert [m.arbitration_id for m in logged] == [0x200, 0x205]
    # both stamped on the wall clock within the test's run (ASC keeps time since its start)
    start = 0.0 if suffix == '.asc' else started
    assert all(start - 1.0 <= m.timestamp <= start + (time.time() - started) + 1.0
               for m in logged)
    if suffix in ('.asc', '.blf', '.log'):  # the formats that keep the direction
        assert [m.is_rx for m in logged] == [False, True]
    if suffix == '.log':  # candump's format: both under the interface's name
        assert [m.channel for m in logged] == [channel, channel]


def test_unknown_log_suffix_is_an_error(tmp_path, channel):
    with pytest.raises(BusError, match='cannot open CAN log'):
        ManagedBus(virtual(channel, log_file=str(tmp_path / 'x.nope')))


def test_bus_config_errors():
    with pytest.raises(HardwareConfigError, match=r'buses\.b\.interface is required'):
        BusConfig.from_dict('b', {'channel': 'can0'})
    with pytest.raises(HardwareConfigError, match=r"unknown key\(s\) \['bitrat'\]"):
        BusConfig.from_dict('b', {'interface': 'virtual', 'bitrat': 1})
    with pytest.raises(HardwareConfigError, match='reconnect_max_s must be >='):
        BusConfig.from_dict(
            'b', {'interface': 'virtual', 'reconnect_initial_s': 1.0, 'reconnect_max_s': 0.5}
        )
    assert BusConfig.from_dict('can0', {'interface': 'socketcan'}).channel == 'can0'


# --- no receive thread: the loop polls ---
def test_when_polled_expect_every_queued_frame_dispatched_at_once_and_no_thread(channel):
    got = []
    with ManagedBus(virtual(channel)) as bus, can.Bus(interface='virtual', channel=channel) as peer:
        bus.add_handler(0x201, lambda msg, now: got.append(msg.data[0]) or True)
        bus.start(receive_thread=False)
        assert bus.poll() == 0
        for i in range(3):
            peer.send(frame(0x201, bytes([i])))
        assert bus.poll() == 3  # everything received so far, without waiting
        assert got == [0, 1, 2]
        assert bus.poll() == 0
        assert not [t for t in threading.enumerate() if t.name == 'canrx-vcan']


def test_when_a_polled_bus_fails_expect_it_reopened_after_the_backoff():
    opened = []

    def factory(**kwargs):
        opened.append(BrokenAtBirth(**kwargs))
        return opened[-1]

    with ManagedBus(fake(), bus_factory=factory) as bus:
        bus.start(receive_thread=False)
        assert bus.poll() == 0  # the receive fails: closed, reopen scheduled in 10 ms
        assert bus.state is BusState.DOWN
        assert len(opened) == 1
        bus.poll()  # within the back-off: nothing
        assert wait_until(lambda: bus.poll() == 0 and len(opened) >= 2, TIMEOUT)
