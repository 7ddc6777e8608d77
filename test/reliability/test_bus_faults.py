"""Bus faults against the running CAN hardware layer: its own threads, rm_sim in real time.

The adapter disappears (receive and send raise, and it cannot be reopened for a while),
the transmit buffer stays full (send raises), or the simulated bus goes bus-off (nothing
moves, send raises). Each must be logged, the bus reopened with back-off, nothing may
crash (the 1 kHz scheduler keeps ticking without errors), every joint must output zero
while the bus is down and — back up — until a command newer than the recovery; and the
unsafe-frame checker must find nothing on the wire in the whole run.

The hardware runs with its real scheduler and receive threads here (reconnection lives in
the receive thread), so waits are on conditions with generous timeouts, and the checker's
timing grace is 50 ms for CPU steal on the shared VM.

Already covered elsewhere and not repeated: reopen with exponential back-off of a bare
ManagedBus and its counters (test/unit/hardware/test_bus.py), one receive error with a
virtual bus -> zero until commanded (test/unit/hardware/test_can_hardware.py), bus-off
through the node's sim service (test/integration/test_bridge_node.py).
"""

from __future__ import annotations

import logging
import threading
import time

import can
import pytest
from rm_base.hardware import MODE_OFF, MODE_VELOCITY, BusState, CanHardware
from rm_base.sim import SimBus, SimWorld
from support.ros import wait_until

from reliability.rigs import FlakyAdapter, unique_channel
from reliability.wire import WireChecker
from rm_base import motors as motor_families

pytestmark = pytest.mark.realtime

WAIT = 10.0  # [s] longest wait for any condition
GRACE = 0.05  # [s] checker timing grace in real time (CPU steal)

JOINTS = {
    'wheel': {
        'type': 'm3508',
        'bus': 'can0',
        'id': 1,
        'velocity_pid': {'kp': 0.5, 'ki': 5.0, 'integral_separation': 3.0, 'output_limit': 6.0},
    },
    'rear': {
        'type': 'm3508',
        'bus': 'can0',
        'id': 2,
        'velocity_pid': {'kp': 0.5, 'ki': 5.0, 'integral_separation': 3.0, 'output_limit': 6.0},
    },
}


class RealtimeRig:
    """CanHardware (started) on a real-time world through a FlakyAdapter, a driver thread
    commanding both wheels at 100 Hz (as a plugin would), and a tap feeding the checker."""

    def __init__(self) -> None:
        self.channel = unique_channel('bus')
        self.world = SimWorld()
        self.world.add_channel(
            self.channel,
            [
                {'type': 'm3508', 'id': 1, 'name': 'wheel'},
                {'type': 'm3508', 'id': 2, 'name': 'rear'},
            ],
        )
        self.world.start()
        self.config = {
            'buses': {
                'can0': {
                    'interface': 'rm_sim',
                    'channel': self.channel,
                    'reconnect_initial_s': 0.01,
                    'reconnect_max_s': 0.04,
                    'receive_timeout_s': 0.01,
                }
            },
            'joints': JOINTS,
        }
        self.adapter = FlakyAdapter(self.world)
        self.hw = CanHardware(self.config, bus_factory=self.adapter, families=motor_families)
        self.bus = self.hw.buses['can0']
        self.tap = SimBus(self.channel, world=self.world, rx_queue_size=0)
        self.checker = WireChecker(self.config, grace_s=GRACE, record=True)
        self.command = {'mode': MODE_VELOCITY, 'velocity': 20.0}
        self._stop = threading.Event()
        self._driver = threading.Thread(target=self._drive, daemon=True)
        self.hw.start()
        self._driver.start()

    def _drive(self) -> None:
        while not self._stop.wait(0.01):
            for joint in JOINTS:
                self.hw.set_command(joint, **self.command)

    def close(self) -> None:
        self._stop.set()
        self._driver.join(timeout=5.0)
        self.hw.shutdown()
        self.tap.shutdown()
        self.world.close()

    def drain(self) -> None:
        while (msg := self.tap.recv(0.0)) is not None:
            self.checker.feed('can0', msg)

    def driven(self, since: float) -> bool:
        self.drain()
        return all(sum(n for t, _, n in self.checker.timeline(j) if t > since) >= 5 for j in JOINTS)

    def held(self) -> bool:
        """Every joint reports zero output (MODE_OFF) right now."""
        return all(s.mode == MODE_OFF and s.command == 0.0 for s in self.hw.states())


@pytest.fixture
def rig():
    r = RealtimeRig()
    assert wait_until(lambda: r.driven(0.0), WAIT)
    yield r
    r.close()


def assert_no_unsafe_frame(rig):
    rig.drain()
    assert rig.checker.violation_count == 0, '\n'.join(map(str, rig.checker.violations))


def watch_while(rig, condition, timeout=WAIT):
    """Sample the hardware while condition() holds; return (samples, all held zero)."""
    samples, zero = 0, True
    ticks = rig.hw.scheduler.stats().ticks
    deadline = time.monotonic() + timeout
    while condition() and time.monotonic() < deadline:
        samples += 1
        zero = zero and rig.held()
        time.sleep(0.002)
    assert rig.hw.scheduler.stats().ticks > ticks  # the 1 kHz loop went on
    return samples, zero


def frames_after_gap(rig, since):
    """(wire time, non-zero) of every command to the wheel after ``since``."""
    rig.drain()
    return [(t, nonzero) for t, _, nonzero in rig.checker.timeline('wheel') if t > since]


def test_when_the_adapter_disappears_and_cannot_reopen_for_a_while_expect_zero_and_back_off(
    rig, caplog
):
    caplog.set_level(logging.WARNING, logger='rm_base.hardware')
    rig.adapter.refuse_opens = 4  # the next four opens fail: the device is gone
    rig.adapter.gone.set()  # receive and send raise on the open bus
    assert wait_until(lambda: rig.bus.state is BusState.DOWN, WAIT)
    gone = time.time()
    samples, zero = watch_while(rig, lambda: rig.adapter.refused < 4)
    assert samples > 0 and zero, 'a joint had output while the bus was down'
    rig.adapter.gone.clear()  # plugged back in
    back = time.time()
    assert wait_until(lambda: rig.bus.state is BusState.UP, WAIT)
    assert rig.hw.scheduler.stats().errors == 0

    # logged, with back-off: 10 ms doubling up to the 40 ms cap while opens fail
    messages = [r.getMessage() for r in caplog.records]
    assert any('receive failed' in m and 'adapter gone' in m for m in messages)
    delays = [m.split('reopening in ')[1] for m in messages if 'reopening in' in m]
    assert delays[:5] == ['0.010 s', '0.020 s', '0.040 s', '0.040 s', '0.040 s'], delays
    stats = rig.bus.stats()
    assert stats.open_failures >= 4 and stats.reopen_count >= 1
    # back: the first frame on the wire is zero, then the fresh commands drive again
    assert wait_until(lambda: rig.driven(back), WAIT)
    after = frames_after_gap(rig, gone)
    assert after and not after[0][1], after[:3]
    assert_no_unsafe_frame(rig)


def test_when_the_transmit_buffer_stays_full_expect_a_reopen_and_no_crash(rig, caplog):
    caplog.set_level(logging.WARNING, logger='rm_base.hardware')
    reopens = rig.bus.stats().reopen_count
    rig.adapter.tx_full.set()
    assert wait_until(lambda: rig.bus.stats().reopen_count > reopens, WAIT)
    assert rig.bus.stats().send_errors >= 20  # send_failures_to_reopen
    rig.adapter.tx_full.clear()
    back = time.time()
    assert wait_until(lambda: rig.driven(back), WAIT)
    assert any('Transmit buffer full' in r.getMessage() for r in caplog.records)
    assert rig.hw.scheduler.stats().errors == 0
    assert_no_unsafe_frame(rig)


def test_when_the_bus_goes_bus_off_expect_zero_while_off_and_on_return(rig, caplog):
    caplog.set_level(logging.WARNING, logger='rm_base.hardware')
    channel = rig.world.channel(rig.channel)
    channel.set_state(can.BusState.ERROR)  # nothing moves in either direction
    off = time.time()
    # the feedback stops: every joint is offline (zero) within the feedback timeout
    assert wait_until(lambda: not any(s.online for s in rig.hw.states()), WAIT)
    samples, zero = watch_while(rig, lambda: time.time() < off + 0.5)
    assert samples > 0 and zero
    reopens = rig.bus.stats().reopen_count
    channel.set_state(can.BusState.ACTIVE)
    back = time.time()
    assert wait_until(lambda: rig.driven(back), WAIT)
    after = frames_after_gap(rig, off)
    assert after and not after[0][1], after[:3]
    assert reopens >= 1 and rig.hw.scheduler.stats().errors == 0
    assert any('bus-off' in r.getMessage() for r in caplog.records)
    print(f'bus-off 0.5 s: {reopens} reopen(s), {len(caplog.records)} warning line(s)')
    assert_no_unsafe_frame(rig)
