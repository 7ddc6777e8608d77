"""The simulated super-capacitor board: its energy, what the referee measures, its frames."""

from types import SimpleNamespace

import pytest
from rm_base.hardware.protocols import supercap as protocol
from rm_base.sim import SimBus, SimConfigError, SimWorld
from rm_base.sim.supercap import SimSupercap, supercap_from_config

from .helpers import drain, send, unique_channel

MS = 1_000_000
DT = 0.001
VALUES = {'capacity_j': 100.0, 'energy': 0.5, 'max_charge_w': 150.0, 'max_discharge_w': 300.0,
          'efficiency': 0.9, 'command_timeout_s': 0.1}


def wheel(power_w):
    return SimpleNamespace(powered=True, model=SimpleNamespace(electrical_power=power_w))


def board(power_w, **values):
    wheels = [wheel(power_w / 2), wheel(power_w / 2)]
    return SimSupercap('can0', wheels, {**VALUES, **values}), wheels


def command(cap, limit_w, now_ns=0, enable=True):
    data = protocol.encode_command(limit_w, 60.0, enable=enable)
    assert cap.receive(protocol.COMMAND_ID, data, now_ns) == []


def test_above_the_limit_the_capacitor_gives_the_rest_and_the_referee_sees_the_limit():
    cap, _ = board(140.0)
    command(cap, 60.0)
    cap.step(MS, DT)
    assert cap.input_power_w == pytest.approx(60.0)
    assert cap.energy_j == pytest.approx(50.0 - 80.0 / 0.9 * DT)


def test_below_the_limit_it_charges_with_what_the_wheels_leave_until_full():
    cap, _ = board(20.0)
    command(cap, 60.0)
    cap.step(MS, DT)
    assert cap.input_power_w == pytest.approx(60.0)
    assert cap.energy_j == pytest.approx(50.0 + 40.0 * 0.9 * DT)
    full, _ = board(20.0, energy=1.0)
    command(full, 60.0)
    full.step(MS, DT)
    assert (full.input_power_w, full.energy_j) == (pytest.approx(20.0), 100.0)


def test_empty_it_gives_nothing_and_the_referee_sees_the_wheels():
    cap, _ = board(140.0, energy=0.0)
    command(cap, 60.0)
    cap.step(MS, DT)
    assert (cap.input_power_w, cap.energy_j) == (pytest.approx(140.0), 0.0)


@pytest.mark.parametrize('why', ['no command', 'disabled', 'timed out', 'error'])
def test_not_working_it_passes_the_wheels_power_through(why):
    cap, _ = board(140.0)
    now = MS
    if why == 'disabled':
        command(cap, 60.0, enable=False)
    elif why == 'timed out':
        command(cap, 60.0)
        now = 101 * MS
    elif why == 'error':
        command(cap, 60.0)
        cap.errors = protocol.CapError.SHORT_CIRCUIT
    cap.step(now, DT)
    assert (cap.input_power_w, cap.energy_j) == (pytest.approx(140.0), 50.0)


def test_a_malformed_command_is_counted_and_ignored():
    cap, _ = board(0.0)
    assert cap.receive(protocol.COMMAND_ID, bytes(3), 0) == []
    assert (cap.ignored, cap.command) == (1, None)


def test_its_config_is_checked():
    with pytest.raises(SimConfigError, match=r'supercap\.channel'):
        supercap_from_config({'capacity_j': 10.0}, [])
    with pytest.raises(SimConfigError, match='capacity_j'):
        supercap_from_config({'channel': 'can0', 'capacity_j': -1.0}, [])


def test_in_a_world_it_reads_0x061_and_reports_on_0x051_every_tick_and_feeds_the_referee(
        tmp_path):
    channel = unique_channel()
    wheels = ['fl', 'fr', 'rl', 'rr']
    world = SimWorld.from_config({
        'timing': 'stepped',
        'channels': {channel: [{'type': 'm3508', 'id': i + 1, 'name': n}
                               for i, n in enumerate(wheels)]},
        'body': {'chassis': {'type': 'mecanum', 'motors': wheels, 'wheelbase': 0.4,
                             'track': 0.4, 'wheel_radius': 0.0763}},
        'supercap': {'channel': channel, 'energy': 0.5},
        'referee': {'path': str(tmp_path / 'referee')},
    })
    with world, SimBus(channel=channel) as bus:
        assert world.serial.referee.supply is world.supercap
        send(bus, protocol.COMMAND_ID, protocol.encode_command(80.0, 60.0))
        world.step(3)
        frames = [m for m in drain(bus) if m.arbitration_id == protocol.FEEDBACK_ID]
        assert len(frames) == 3
        feedback = protocol.decode_feedback(bytes(frames[-1].data))
        assert feedback.limit_w == 80 and feedback.energy == pytest.approx(0.5, abs=0.01)
        assert world.supercap.commands == 1
