"""The loop's order comes from what its components read and write; the checks name them."""

import pytest
from rm_base.control import ChassisPowerModel
from rm_base.hardware import CanHardware
from rm_base.hardware.actuators import Mode
from rm_base.loop import LoopConfigError, Scheduler
from rm_base.loop.data import COMMANDS, JOINT_EFFORTS, JOINT_STATES, JOINT_TARGETS, PUBLISHED
from rm_base.loop.order import derive_order, unread_outputs
from support.hardware import MS, T0
from support.hardware import feed_dji as feed

from rm_base import motors as motor_families


class Part:
    """A component that only declares its data and records its runs."""

    def __init__(self, name, reads=(), writes=(), runs=None):
        self.name, self.reads, self.writes = name, tuple(reads), tuple(writes)
        self.runs = runs if runs is not None else []

    def __call__(self, now_ns, dt):
        self.runs.append(self.name)
        return True


def names(parts, order):
    return [parts[i].name for i in order]


def test_writers_run_before_modifiers_before_readers_whatever_the_order_added():
    parts = [
        Part('reader', reads=['x']),
        Part('second modifier', reads=['x'], writes=['x']),
        Part('first modifier', reads=['x'], writes=['x']),
        Part('writer', writes=['x']),
        Part('unrelated'),
    ]
    order = names(parts, derive_order(parts))
    # the modifiers keep the order they were added in; what declares nothing keeps its place
    assert order == ['writer', 'second modifier', 'first modifier', 'reader', 'unrelated']


def test_a_cycle_is_an_error_naming_both_components_and_the_data_they_need():
    parts = [Part('a', reads=['y'], writes=['x']), Part('b', reads=['x'], writes=['y'])]
    with pytest.raises(LoopConfigError, match='form a cycle') as caught:
        derive_order(parts)
    assert "'a' needs 'y' from 'b'" in str(caught.value)
    assert "'b' needs 'x' from 'a'" in str(caught.value)


def test_a_cycle_of_three_names_each_step():
    parts = [
        Part('a', reads=['z'], writes=['x']),
        Part('b', reads=['x'], writes=['y']),
        Part('c', reads=['y'], writes=['z']),
        Part('fine', writes=['w']),
    ]
    with pytest.raises(LoopConfigError) as caught:
        derive_order(parts)
    text = str(caught.value)
    assert all(f"'{n}' needs" in text for n in 'abc') and 'fine' not in text


def test_an_output_nothing_reads_is_named_with_its_last_writer():
    parts = [Part('w', writes=['x']), Part('m', reads=['x'], writes=['x'])]
    assert unread_outputs(parts) == [('m', 'x')]
    assert unread_outputs([*parts, Part('r', reads=['x'])]) == []


def test_a_scheduler_refuses_a_stage_whose_output_nothing_reads_unless_composing():
    loop = Scheduler([], [])
    with pytest.raises(LoopConfigError, match="'port imu' writes 'imu data'"):
        loop.add_stage(Part('port imu', writes=['imu data']))
    assert 'port imu' not in loop.order()  # refused whole
    loop.add_after_tick(lambda: None, reads=(PUBLISHED,))
    with loop.compose():  # the port first, its reader later: checked at the end
        loop.add_stage(Part('port imu', writes=['imu data']))
        loop.add_stage(Part('plugin imu', reads=['imu data', COMMANDS], writes=[PUBLISHED]))
    assert loop.order()[:2] == ('port imu', 'plugin imu')
    with pytest.raises(LoopConfigError, match="'plugin lone' writes 'lone data'"):
        with loop.compose():
            loop.add_stage(Part('plugin lone', writes=['lone data']))


def test_a_scheduler_refuses_a_stage_that_closes_a_cycle_and_keeps_its_order():
    loop = Scheduler([], [])
    loop.add_stage(Part('plugin', reads=[JOINT_STATES], writes=[JOINT_TARGETS]))
    before = loop.order()
    # it would write the states the actuators read from the efforts they write
    with pytest.raises(LoopConfigError, match="'bad' needs 'joint efforts' from 'actuators'"):
        loop.add_stage(Part('bad', reads=[JOINT_EFFORTS], writes=[JOINT_STATES]))
    assert loop.order() == before


class CapacitorLimit:
    """A second power limiter: caps each wheel's effort at what the capacitor allows.

    It is a component like any: it declares what it reads (the efforts, the capacitor's
    state) and that it modifies the efforts; nothing else tells the loop where it goes.
    """

    name = 'capacitor limit'
    reads = (JOINT_EFFORTS, 'capacitor')
    writes = (JOINT_EFFORTS,)

    def __init__(self, actuators, capacitor):
        self.actuators, self.capacitor = actuators, capacitor

    def __call__(self, now_ns, dt):
        cap = self.capacitor.allowed_effort
        for actuator in self.actuators:
            if abs(actuator.effort_out) > cap:
                actuator.scale_output(cap / abs(actuator.effort_out))
        return True


class Capacitor:
    """The capacitor's feedback as a stage: writes its state each tick."""

    name = 'capacitor feedback'
    reads = ()
    writes = ('capacitor',)

    def __init__(self):
        self.allowed_effort = None

    def __call__(self, now_ns, dt):
        self.allowed_effort = 0.5
        return True


def test_a_second_power_limiter_joins_by_declaring_its_data_and_both_limit(channel):
    hw = CanHardware({
        'buses': {'can0': {'interface': 'virtual', 'channel': channel}},
        'joints': {f'w{i}': {'type': 'm3508', 'bus': 'can0', 'id': i} for i in range(1, 5)},
    }, families=motor_families)
    wheels = [hw.actuators[f'w{i}'] for i in range(1, 5)]
    # the referee's limit: 3 W/(N*m)^2 copper loss, at rest: 3 * (2 * 2^2 + 2 * 0.6^2) =
    # 26.16 W asked, 6.54 W allowed -> every effort times 1/2
    model = ChassisPowerModel(k1=3.0, k2=0.0)
    first = hw.add_power_limit('chassis', [w.name for w in wheels], model)
    first.limit_w = 6.54
    capacitor = Capacitor()
    # added in the "wrong" order: the limiter before the feedback it reads
    with hw.scheduler.compose():
        hw.scheduler.add_stage(CapacitorLimit(wheels, capacitor))
        hw.scheduler.add_stage(capacitor)
    assert hw.scheduler.order() == (
        'feedback', 'capacitor feedback', 'actuators', 'power limit chassis', 'capacitor limit',
        'pack', 'send',
    )
    for i, wheel in enumerate(wheels):
        feed(wheel, T0)
        wheel.set_command(Mode.EFFORT, T0, effort=2.0 if i < 2 else 0.6)
    hw.scheduler.tick(T0 + MS)
    # the referee's limit halves every effort (2 -> 1, 0.6 -> 0.3); the capacitor's then
    # caps the first two at 0.5 and leaves the others
    assert first.last.scale == pytest.approx(0.5, abs=0.01)
    assert [w.effort_out for w in wheels] == pytest.approx([0.5, 0.5, 0.3, 0.3], abs=0.01)
