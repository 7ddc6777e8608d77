"""Shared helpers of the hardware and motor family tests."""

import itertools
import os
import time

import can
from rm_base.hardware.config import JointConfig
from rm_base.motors.dji import protocol as dji
from rm_base.sim.bus import SimBus

MS = 1_000_000  # ns
T0 = 1_000 * MS

_channels = itertools.count()


class FakeClock:
    """A monotonic clock [ns] that only moves when the test says so."""

    def __init__(self, start_ns: int = T0) -> None:
        self.now_ns = start_ns

    def __call__(self) -> int:
        return self.now_ns

    def advance_ms(self, ms: float) -> int:
        self.now_ns += int(ms * MS)
        return self.now_ns


def unique_channel() -> str:
    """A python-can virtual channel no other test uses."""
    return f'rm-hw-test-{os.getpid()}-{next(_channels)}'


def joint(name='j', type='m3508', bus='can0', id=1, **extra):
    return JointConfig.from_dict(name, {'type': type, 'bus': bus, 'id': id, **extra})


def sim_factory(interface, channel, ignore_config=True, **kwargs):
    assert interface == 'rm_sim'
    kwargs.pop('bitrate', None)
    return SimBus(channel=channel, **kwargs)


def wait_fresh(hw, now_ns, timeout_s=10.0):
    """Busy-wait (briefly) until every joint has feedback stamped at now_ns."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if all(
            a.feedback is not None and a.feedback.stamp_ns >= now_ns for a in hw.actuators.values()
        ):
            return
        time.sleep(0.0002)
    raise AssertionError(f'no fresh feedback: {hw.states()}')


def feed_dji(actuator, now_ns, ticks=0, rpm=0, current=0, temperature=30):
    """Hand a DJI actuator one feedback frame with these raw values."""
    msg = can.Message(
        arbitration_id=actuator.feedback_id,
        data=dji.encode_feedback(ticks, rpm, current, temperature),
        is_extended_id=False,
    )
    assert actuator.handle_frame(msg, now_ns)
