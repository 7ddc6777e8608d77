"""Fault injection into simulated motors: offline, jam, over-temperature, garbage, clear."""

import pytest
from rm_base.motors.dji import protocol as dji
from rm_base.sim import Fault, FaultKind, SimBus, SimConfigError, SimLookupError, SimWorld

from .helpers import drain, send, unique_channel


def frames_on(frames, can_id):
    return [f for f in frames if f.arbitration_id == can_id]


def test_when_offline_expect_no_feedback_and_commands_ignored(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    device = bus.sim.motor('w')
    bus.sim.inject('w', Fault.offline())
    send(bus, 0x200, dji.pack_command([4096]))
    bus.sim.step(50)
    assert drain(bus) == []
    assert device.command_raw == 0
    assert device.stats.rx_frames == 0
    assert not device.online


def test_when_offline_cleared_expect_feedback_resumes(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    bus.sim.inject('w', Fault.offline())
    bus.sim.step(10)
    bus.sim.clear_faults('w', FaultKind.OFFLINE)
    bus.sim.step(10)
    assert len(frames_on(drain(bus), 0x201)) == 10


def test_when_offline_dji_motor_times_out_to_zero_current(make_bus):
    # Unplugged from the bus, the ESC stops hearing commands: after the 100 ms timeout
    # it cuts the current, like a real C620 whose CAN wire comes off.
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    device = bus.sim.motor('w')
    device.model.locked = True
    send(bus, 0x200, dji.pack_command([4096]))
    bus.sim.inject('w', Fault.offline())
    bus.sim.step(150)
    assert device.model.current == 0.0


def test_when_jammed_expect_locked_rotor_with_current(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    device = bus.sim.motor('w')
    bus.sim.inject('w', Fault.jam())
    for _ in range(50):
        send(bus, 0x200, dji.pack_command([8192]))  # 10 A
        bus.sim.step()
    assert device.model.velocity == 0.0
    assert device.model.current == pytest.approx(10.0)
    fb = dji.decode_feedback(frames_on(drain(bus), 0x201)[-1].data)
    assert fb.rotor_rpm == 0
    assert fb.current_raw == 8192


@pytest.mark.parametrize(('amps', 'moves'), [(2.0, False), (4.0, True)])
def test_when_jammed_with_load_torque_expect_hold_below_it(make_bus, amps, moves):
    # Load 1.0 N·m plus Coulomb 0.1 N·m: 2 A * 0.3 = 0.6 N·m holds, 4 A = 1.2 N·m turns.
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    device = bus.sim.motor('w')
    bus.sim.inject('w', {'kind': 'jam', 'load_torque': 1.0})
    send(bus, 0x200, dji.pack_command([round(amps * 16384 / 20)]))
    bus.sim.step(50)
    assert (device.model.velocity > 0.0) is moves


def test_when_jam_cleared_expect_rotor_free(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    device = bus.sim.motor('w')
    bus.sim.inject('w', Fault.jam())
    bus.sim.clear_faults('w')
    send(bus, 0x200, dji.pack_command([4096]))
    bus.sim.step(20)
    assert device.model.velocity > 0.0


def test_when_over_temperature_expect_forced_temperature_reported(make_bus):
    bus = make_bus([{'type': 'gm6020', 'id': 1, 'name': 'yaw'}])
    bus.sim.inject('yaw', Fault.over_temperature(110.0))
    bus.sim.step(3)
    temps = [dji.decode_feedback(f.data).temperature_c for f in frames_on(drain(bus), 0x205)]
    assert temps == [110, 110, 110]


def test_when_over_temperature_cleared_expect_cooling_from_there(make_bus):
    bus = make_bus([{'type': 'gm6020', 'id': 1, 'name': 'yaw'}])
    device = bus.sim.motor('yaw')
    bus.sim.inject('yaw', Fault.over_temperature(110.0))
    bus.sim.step()
    bus.sim.clear_faults('yaw')
    bus.sim.step(1000)
    assert 25.0 < device.model.temperature < 110.0


def test_when_garbage_on_own_id_expect_extra_frames_at_rate(make_bus):
    # 100 Hz of garbage over 100 ms: 10 frames on 0x201 beside the 100 real ones.
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    bus.sim.inject('w', Fault.garbage(rate_hz=100.0))
    bus.sim.step(100)
    frames = frames_on(drain(bus), 0x201)
    assert len(frames) == 110
    assert bus.sim.motor('w').stats.garbage_frames == 10


def test_when_garbage_on_random_ids_expect_frames_elsewhere(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    bus.sim.inject('w', Fault.garbage(rate_hz=1000.0, random_ids=True))
    bus.sim.step(50)
    others = [f for f in drain(bus) if f.arbitration_id != 0x201]
    assert len({f.arbitration_id for f in others}) > 10
    assert all(f.arbitration_id <= 0x7FF and len(f.data) == 8 for f in others)


def test_garbage_is_repeatable_with_the_same_seed():
    def run(seed):
        with SimWorld(timing='stepped', seed=seed) as world:
            name = unique_channel()
            world.add_channel(name, [{'type': 'm3508', 'id': 1, 'name': 'w'}])
            world.inject('w', Fault.garbage(rate_hz=1000.0, random_ids=True))
            with SimBus(name, world=world) as bus:
                world.step(20)
                return [(f.arbitration_id, bytes(f.data)) for f in drain(bus)]

    assert run(7) == run(7)
    assert run(7) != run(8)


def test_when_all_faults_cleared_expect_normal_motor(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}, {'type': 'm3508', 'id': 2}])
    for fault in (Fault.jam(), Fault.garbage(), Fault.over_temperature(), Fault.offline()):
        bus.sim.inject('w', fault)
    bus.sim.inject('m3508_2', Fault.offline())
    assert set(bus.sim.motor('w').faults) == set(FaultKind)
    bus.sim.clear_faults()
    device = bus.sim.motor('w')
    assert device.faults == {}
    assert not device.model.locked
    assert device.model.temperature_override is None
    assert bus.sim.motor('m3508_2').online


@pytest.mark.parametrize(
    ('config', 'message'),
    [
        ({'kind': 'melt'}, "unknown fault kind 'melt'"),
        ({}, 'needs a kind'),
        ({'kind': 'offline', 'rate_hz': 5}, 'offline fault takes no parameters'),
        ({'kind': 'jam', 'load_torque': -1.0}, 'load_torque must be >= 0'),
        ({'kind': 'garbage', 'rate_hz': 0}, 'rate_hz must be > 0'),
        ({'kind': 'over_temperature', 'temperature': 400}, 'must be -40..255'),
    ],
)
def test_when_bad_fault_config_expect_config_error(config, message):
    with pytest.raises(SimConfigError, match=message):
        Fault.from_config(config)


def test_fault_from_config_builds_the_fault():
    fault = Fault.from_config({'kind': 'garbage', 'rate_hz': 50, 'random_ids': True})
    assert fault == Fault.garbage(rate_hz=50, random_ids=True)


def test_when_fault_for_unknown_motor_expect_lookup_error(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    with pytest.raises(SimLookupError, match="no motor 'x'"):
        bus.sim.inject('x', Fault.offline())
    with pytest.raises(SimConfigError, match='unknown fault kind'):
        bus.sim.clear_faults('w', 'melt')


def test_when_garbage_on_a_command_id_expect_other_motors_hear_it(make_bus):
    # A rogue node spamming 0x200 drives the C620 with id 1 with random slot values.
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'victim'}, {'type': 'gm6020', 'id': 3}])
    bus.sim.inject('gm6020_3', Fault.garbage(rate_hz=1000.0, can_id=0x200))
    bus.sim.step(5)
    victim = bus.sim.motor('victim')
    assert victim.stats.rx_frames == 5
    assert victim.command_raw != 0
    assert len(frames_on(drain(bus), 0x200)) == 5


def test_a_motor_does_not_hear_its_own_garbage(make_bus):
    bus = make_bus([{'type': 'm3508', 'id': 1, 'name': 'w'}])
    bus.sim.inject('w', Fault.garbage(rate_hz=1000.0, can_id=0x200))
    bus.sim.step(5)
    assert bus.sim.motor('w').stats.rx_frames == 0
