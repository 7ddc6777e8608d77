"""The super-capacitor device: its states, the power it allows, the frames it sends."""

import math

import can
import pytest
from rm_base.errors import InputRejectedError
from rm_base.hardware import CanHardware, HardwareConfigError
from rm_base.hardware.protocols import supercap as protocol
from rm_base.hardware.supercap import CapState, PowerSupply, Supercap, SupercapConfig
from support.hardware import MS, T0, unique_channel

from rm_base import motors as motor_families

CONFIG = SupercapConfig(bus='can0', timeout_s=0.05, fault_clear_s=0.5, reserve=0.3,
                        recharge_to=0.5, charge_w=15.0, burst_w=100.0)
REFEREE = PowerSupply(referee_limit_w=80.0, buffer_j=60.0)
BURST = PowerSupply(referee_limit_w=80.0, buffer_j=60.0, request_w=250.0)


def frame(energy=0.8, errors=0, power=40.0):
    return can.Message(arbitration_id=protocol.FEEDBACK_ID, is_extended_id=False,
                       data=protocol.encode_feedback(errors, power, 80, energy))


def clean(cap, start_ns=T0, seconds=0.6, energy=0.8):
    """Feed clean frames every ms for seconds; return the time after the last."""
    now = start_ns
    for _ in range(round(seconds * 1000)):
        assert cap.handle_frame(frame(energy), now)
        now += MS
    return now - MS


def test_unheard_the_capacitor_changes_nothing():
    cap = Supercap(CONFIG, 1000.0)
    assert cap.state(T0) is CapState.OFFLINE
    assert cap.allow(70.0, BURST, T0) == 70.0


def test_it_is_used_only_after_clean_feedback_for_fault_clear_s():
    cap = Supercap(CONFIG, 1000.0)
    now = clean(cap, seconds=0.4)
    assert cap.state(now) is CapState.FAULT  # 0.4 s of evidence, 0.5 s asked
    assert cap.allow(70.0, BURST, now) == 70.0
    now = clean(cap, now + MS, seconds=0.2)
    assert cap.state(now) is CapState.READY
    assert cap.allow(70.0, REFEREE, now) == 80.0  # the referee's limit, not the buffer's
    assert cap.allow(70.0, BURST, now) == 180.0  # referee + burst_w
    assert cap.state(now) is CapState.BURST
    request = PowerSupply(referee_limit_w=80.0, buffer_j=60.0, request_w=120.0)
    assert cap.allow(70.0, request, now) == 120.0
    lower = PowerSupply(referee_limit_w=80.0, buffer_j=60.0, request_w=50.0)
    assert cap.allow(50.0, lower, now) == 50.0


def test_an_error_bit_falls_back_at_once_and_clears_on_evidence_only():
    cap = Supercap(CONFIG, 1000.0)
    now = clean(cap)
    assert cap.handle_frame(frame(errors=protocol.CapError.UNDER_VOLTAGE), now + MS)
    assert cap.state(now + MS) is CapState.FAULT
    assert cap.allow(70.0, BURST, now + MS) == 70.0
    assert cap.report(now + MS)['errors'] == 'under voltage'
    now = clean(cap, now + 2 * MS, seconds=0.45)
    assert cap.state(now) is CapState.FAULT  # one clean frame is not evidence
    now = clean(cap, now + MS, seconds=0.1)
    assert cap.state(now) is CapState.READY


def test_a_silence_is_offline_and_the_first_frame_after_it_starts_the_evidence_again():
    cap = Supercap(CONFIG, 1000.0)
    now = clean(cap)
    late = now + 60 * MS
    assert cap.state(late) is CapState.OFFLINE
    assert cap.allow(70.0, BURST, late) == 70.0
    assert cap.handle_frame(frame(), late)
    assert cap.state(late) is CapState.FAULT


def test_below_the_reserve_it_refills_to_recharge_to_and_no_burst_meanwhile():
    cap = Supercap(CONFIG, 1000.0)
    now = clean(cap)
    now = clean(cap, now + MS, seconds=0.01, energy=0.29)
    assert cap.state(now) is CapState.CHARGING
    assert cap.allow(70.0, BURST, now) == 65.0  # 80 - charge_w
    now = clean(cap, now + MS, seconds=0.01, energy=0.45)
    assert cap.allow(70.0, BURST, now) == 65.0  # latched until recharge_to
    now = clean(cap, now + MS, seconds=0.01, energy=0.5)
    assert cap.allow(70.0, BURST, now) == 180.0


def test_the_referee_unheard_the_plugins_limit_is_the_base_and_is_sent():
    cap = Supercap(CONFIG, 1000.0)
    now = clean(cap)
    unheard = PowerSupply(request_w=250.0)
    assert cap.allow(60.0, unheard, now) == 160.0
    sent = [cap.pack_command() for _ in range(10)]
    assert sent[:9] == [None] * 9  # every period_s (10 ticks at 1 kHz)
    assert protocol.decode_command(bytes(sent[9].data)) == (True, False, 60, 0)


def test_the_command_carries_the_referees_numbers():
    cap = Supercap(CONFIG, 1000.0)
    cap.allow(70.0, REFEREE, T0)
    frames = [m for m in (cap.pack_command() for _ in range(30)) if m is not None]
    assert len(frames) == 3
    assert bytes(frames[0].data) == bytes.fromhex('01 50 00 3C 00 00 00 00')
    assert frames[0].arbitration_id == 0x061


def test_a_bad_frame_is_counted_and_changes_nothing():
    cap = Supercap(CONFIG, 1000.0)
    now = clean(cap)
    bad = can.Message(arbitration_id=protocol.FEEDBACK_ID, is_extended_id=False, data=bytes(5))
    assert cap.handle_frame(bad, now + MS)
    assert cap.decode_errors == 1
    assert cap.state(now + MS) is CapState.READY
    other = can.Message(arbitration_id=0x201, is_extended_id=False, data=bytes(8))
    assert not cap.handle_frame(other, now)


@pytest.mark.parametrize('fields', [
    {'request_w': math.nan}, {'request_w': -1.0}, {'referee_limit_w': math.inf},
    {'referee_limit_w': -5.0}, {'buffer_j': math.inf},
])
def test_a_supply_with_a_bad_number_is_refused(fields):
    with pytest.raises(InputRejectedError):
        PowerSupply(**fields)


def hardware_config(channel, **supercap):
    return {
        'buses': {'can0': {'interface': 'virtual', 'channel': channel}},
        'joints': {f'w{i}': {'type': 'm3508', 'bus': 'can0', 'id': i} for i in range(1, 5)},
        'supercap': {'bus': 'can0', **supercap},
    }


def test_a_supercap_on_an_unknown_bus_or_with_recharge_below_reserve_is_refused():
    with pytest.raises(HardwareConfigError, match=r"supercap\.bus 'can1' is not a configured"):
        CanHardware(hardware_config('x', bus='can1'), families=motor_families)
    with pytest.raises(HardwareConfigError, match=r'recharge_to must be >= supercap\.reserve'):
        CanHardware(hardware_config('x', reserve=0.6), families=motor_families)


def test_in_the_hardware_it_sends_reads_and_feeds_its_groups_stage():
    channel = unique_channel()
    clock = [T0]
    hw = CanHardware(hardware_config(channel), families=motor_families,
                     clock_ns=lambda: clock[0])
    from rm_base.control import ChassisPowerModel

    stage = hw.add_power_limit('chassis', ['w1', 'w2', 'w3', 'w4'],
                               ChassisPowerModel(k1=3.0, k2=0.0, static_power_w=2.0))
    assert stage.supercap is hw.supercap
    other = hw.add_power_limit('arm', ['w1'], ChassisPowerModel(1.0, 0.0, 0.0))
    assert other.supercap is None
    peer = can.Bus(interface='virtual', channel=channel)
    try:
        hw.open()
        stage.supply = REFEREE
        sent = []
        for _ in range(20):
            peer.send(frame(energy=0.7))
            hw.tick(clock[0])
            clock[0] += MS
            while (msg := peer.recv(0.0)) is not None:
                if msg.arbitration_id == protocol.COMMAND_ID:
                    sent.append(bytes(msg.data))
        assert sent == [bytes.fromhex('01 50 00 3C 00 00 00 00')] * 2
        report = hw.diagnostics()['supercap']
        assert report['energy'] == pytest.approx(0.7, abs=1 / 255)
        assert report['state'] == 'fault'  # 20 ms of evidence, 0.5 s asked
        assert report['frames_decoded'] == 20
    finally:
        peer.shutdown()
        hw.shutdown()
