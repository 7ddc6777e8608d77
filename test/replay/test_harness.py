"""The replay harness's fault player on a fake world: a jam locks and frees as it should.

No ROS node here: the simulated world is a small fake.
"""

from __future__ import annotations

from types import SimpleNamespace

from rm_base.sim import FaultKind

from replay.harness import _Faults
from replay.scenarios import Jam


class FakeWorld:
    """A trigger motor whose torque the test sets; fault calls logged."""

    def __init__(self) -> None:
        self.calls: list[tuple] = []
        self.model = SimpleNamespace(torque=0.0, velocity=0.0)

    def motor(self, name):
        return SimpleNamespace(model=self.model)

    def inject(self, motor, fault):
        self.calls.append(('inject', motor, fault.kind))

    def clear_faults(self, motor=None, kind=None):
        self.calls.append(('clear', motor, kind))


def test_a_jam_locks_at_the_next_drive_forward_and_frees_after_a_sustained_reverse():
    world = FakeWorld()
    model = world.model
    faults = _Faults(world, (Jam('trigger', at_s=1.0, torque=0.5, speed=1.0, free_s=0.05),))
    model.torque, model.velocity = 1.5, 10.0
    faults.update(0.9)  # not armed yet
    assert world.calls == []
    model.torque, model.velocity = -1.5, 8.0  # braking at the end of a step
    faults.update(1.0)
    model.torque, model.velocity = 0.8, 0.1  # holding at the end of a step: not moving
    faults.update(1.01)
    assert world.calls == []
    model.torque, model.velocity = 1.5, 3.0  # the next step drives a ball: it wedges
    faults.update(1.03)
    assert world.calls == [('inject', 'trigger', FaultKind.JAM)]
    model.torque, model.velocity = -0.8, 0.0  # the lock's recoil, 20 ms: still jammed
    faults.update(1.04)
    faults.update(1.06)
    model.torque = 1.5  # stalled, pushing on
    faults.update(1.07)
    model.torque = -1.5  # BLOCK reverses, 50 ms: the ball comes free
    for t in (1.20, 1.22, 1.24):
        faults.update(t)
    assert world.calls[-1] == ('inject', 'trigger', FaultKind.JAM)
    faults.update(1.25)
    assert world.calls[-1] == ('clear', 'trigger', FaultKind.JAM)
    assert [r.action for r in faults.records] == ['armed', 'wedged', 'clear']
    assert [r.t for r in faults.records] == [1.0, 1.03, 1.25]
