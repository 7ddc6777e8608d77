"""The unsafe-frame checker itself: it passes safe traffic and flags every unsafe kind.

Frames are built by hand with the protocol encoders, at wire times chosen here; the
checker must not depend on the bridge's actuator code to find a bad frame.
"""

import math
from types import SimpleNamespace

import can
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.hardware.protocols import mit
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.dji import protocol as dji

from reliability.wire import WireChecker, _Window, check_actuator_states, max_efforts

MS = 1e-3
DM4310 = damiao.dm_limits('DM4310')

CONFIG = {
    'buses': {'can0': {'interface': 'virtual', 'channel': 'wire-test'}},
    'joints': {
        # M3508: 0.3 N·m/A at the output, 20 A / 16384 raw -> 1 N·m = 2731 raw
        'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 1, 'max_effort': 1.0},
        'yaw': {'type': 'gm6020', 'bus': 'can0', 'id': 1},  # 1.2 N·m, voltage mode, 0x1FF
        'arm': {'type': 'dm4310', 'bus': 'can0', 'id': 3, 'master_id': 0x13},  # 10 N·m
    },
    'safety': {'feedback_timeout_s': 0.1, 'command_timeout_s': 0.1},
}
ONE_NM = 2731  # raw for 1 N·m on the wheel: 1 / 0.3 A/(N·m)... / (20/16384 A/raw)


def frame(can_id, data, t):
    return can.Message(timestamp=t, arbitration_id=can_id, data=data, is_extended_id=False)


def wheel_fb(t, temperature=30, rpm=0):
    return frame(0x201, dji.encode_feedback(0, rpm, 0, temperature), t)


def yaw_fb(t, rpm=0):
    return frame(0x205, dji.encode_feedback(0, rpm, 0, 30), t)


def arm_fb(t, position=0.0, state=damiao.DmState.ENABLED):
    data = damiao.encode_feedback(
        3,
        state,
        position=position,
        velocity=0.0,
        torque=0.0,
        t_mos=30,
        t_rotor=30,
        limits=DM4310,
    )
    return frame(0x13, data, t)


def wheel_cmd(raw, t):
    return frame(0x200, dji.pack_command([raw]), t)


def arm_cmd(t, **fields):
    cmd = mit.MitCommand(
        **{'position': 0.0, 'velocity': 0.0, 'kp': 0.0, 'kd': 0.0, 'torque': 0.0, **fields}
    )
    return frame(0x03, mit.pack_mit_command(cmd, DM4310), t)


def feed(checker, *frames):
    return checker.feed_all(('can0', f) for f in frames)


def rules(violations):
    return [(v.joint, v.rule) for v in violations]


def test_safe_traffic_is_not_flagged():
    checker = WireChecker(CONFIG)
    for k in range(200):
        t = k * MS
        assert (
            feed(
                checker,
                wheel_fb(t),
                yaw_fb(t),
                arm_fb(t),
                wheel_cmd(ONE_NM, t),
                frame(0x1FF, dji.pack_command([1000]), t),  # yaw: 0.96 V at rest = 0.4 N·m
                arm_cmd(t, position=0.5, kp=5.0, kd=0.3),  # 2.5 N·m, limit 10
            )
            == []
        )
    assert checker.stats('wheel').nonzero_frames == 200
    assert checker.summary()['unsafe_frames'] == 0


def test_a_dji_slot_above_max_effort_is_flagged():
    checker = WireChecker(CONFIG)
    found = feed(checker, wheel_fb(0.0), wheel_cmd(ONE_NM + 2, 0.0))  # 1 raw is the step
    assert rules(found) == [('wheel', 'effort')]
    assert 'beyond max_effort 1.0' in found[0].detail


def test_a_non_zero_slot_without_a_joint_is_flagged():
    checker = WireChecker(CONFIG)
    found = feed(checker, wheel_fb(0.0), frame(0x200, dji.pack_command([0, 0, 5]), 0.0))
    assert rules(found) == [('', 'unknown_slot')]


def test_gm6020_voltage_is_judged_with_the_back_emf_of_its_own_feedback():
    checker = WireChecker(CONFIG)
    # at 100 rpm the back-EMF is 0.716 V·s/rad x 10.47 rad/s = 7.5 V = 7812 raw; 1.2 N·m
    # more is 1.2 / 0.741 A x 1.8 Ω = 2.9 V: 7812 + 3035 raw is the limit, 12000 beyond it
    assert feed(checker, yaw_fb(0.0, rpm=100), frame(0x1FF, dji.pack_command([10800]), 0.0)) == []
    found = feed(checker, yaw_fb(MS, rpm=100), frame(0x1FF, dji.pack_command([12000]), MS))
    assert rules(found) == [('yaw', 'effort')]
    # at rest the same 10800 raw would be 10.4 V = 4.3 N·m
    found = feed(
        checker, yaw_fb(2 * MS), yaw_fb(3 * MS), frame(0x1FF, dji.pack_command([10800]), 3 * MS)
    )
    assert rules(found) == [('yaw', 'effort')]


def test_an_mit_command_asking_more_than_max_effort_is_flagged():
    checker = WireChecker(CONFIG)
    # kp 50 N·m/rad x 0.5 rad = 25 N·m (DM4310 max 10 N·m)
    found = feed(checker, arm_fb(0.0), arm_cmd(0.0, position=0.5, kp=50.0))
    assert rules(found) == [('arm', 'effort')]
    # the same gains near the target ask little
    assert feed(checker, arm_fb(MS, position=0.49), arm_cmd(MS, position=0.5, kp=50.0)) == []


def test_mit_limp_and_system_frames_are_zero():
    checker = WireChecker(CONFIG)
    # never any feedback: only zero (limp) frames and ENABLE/DISABLE may go out
    assert (
        feed(
            checker,
            frame(0x03, mit.system_frame(mit.SystemCommand.ENABLE), 0.0),
            arm_cmd(0.0),
            frame(0x03, mit.system_frame(mit.SystemCommand.DISABLE), MS),
        )
        == []
    )
    assert checker.system_frames == 2
    found = feed(checker, arm_cmd(2 * MS, torque=1.0))
    assert rules(found) == [('arm', 'offline')]


def test_non_zero_after_the_feedback_timeout_plus_grace_is_flagged_and_latency_measured():
    checker = WireChecker(CONFIG, grace_s=0.002)
    feed(checker, wheel_fb(0.0), wheel_cmd(ONE_NM, 0.0))
    # offline from 100 ms on: 101 ms is within the 2 ms grace, 103 ms is not
    assert feed(checker, wheel_cmd(ONE_NM, 0.101)) == []
    found = feed(checker, wheel_cmd(ONE_NM, 0.103))
    assert rules(found) == [('wheel', 'offline')]
    assert '3.0 ms after' in found[0].detail
    feed(checker, wheel_cmd(0, 0.104))
    assert checker.stats('wheel').zero_latencies == [pytest.approx(0.004)]
    # back online: driving is fine again
    assert feed(checker, wheel_fb(0.2), wheel_cmd(ONE_NM, 0.2)) == []


def test_non_zero_while_over_temperature_is_flagged_until_cool_for_the_clear_time():
    checker = WireChecker(CONFIG, grace_s=0.002)
    feed(checker, wheel_fb(0.0, temperature=80), wheel_cmd(ONE_NM, 0.001))  # within grace
    found = feed(checker, wheel_fb(0.005, temperature=76), wheel_cmd(ONE_NM, 0.005))
    assert rules(found) == [('wheel', 'over_temperature')]  # 76 °C: above 80 - 10
    t = 0.01
    for temperature in (72, 69):  # 69 °C: below 80 - 10, the clear time starts here
        feed(checker, wheel_fb(t, temperature=temperature))
        t += 0.01
    cool = t - 0.01
    while t < cool + 1.0:  # safety.fault_clear_s 1 s of cool frames
        found = feed(checker, wheel_fb(t, temperature=69), wheel_cmd(ONE_NM, t + 0.0005))
        assert rules(found) == [('wheel', 'over_temperature')], t - cool
        t += 0.05
    t = cool + 1.0
    assert feed(checker, wheel_fb(t, temperature=69), wheel_cmd(ONE_NM, t + 0.0005)) == []


def test_the_checkers_own_record_of_an_injected_fault_outweighs_what_the_wire_says():
    # A garbage frame saying 28 °C must not make a motor the harness overheated drivable.
    checker = WireChecker(CONFIG, grace_s=0.002)
    feed(checker, wheel_fb(0.0), wheel_cmd(ONE_NM, 0.0005))
    checker.note_fault('wheel', 'over_temperature', 0.001, temperature=123.0)
    found = feed(checker, wheel_fb(0.004, temperature=28), wheel_cmd(ONE_NM, 0.0045))
    assert rules(found) == [('wheel', 'injected_over_temperature')]
    checker.note_fault('wheel', 'over_temperature', 0.5, active=False)
    found = feed(checker, wheel_fb(1.4, temperature=28), wheel_cmd(ONE_NM, 1.4005))
    assert rules(found) == [('wheel', 'injected_over_temperature')]  # within the clear time
    assert feed(checker, wheel_fb(1.51), wheel_cmd(ONE_NM, 1.5105)) == []


def test_an_injected_offline_obliges_zero_after_the_timeout_until_back_for_the_clear_time():
    checker = WireChecker(CONFIG, grace_s=0.002)
    checker.note_fault('wheel', 'offline', 0.0)
    feed(checker, wheel_fb(0.0), wheel_cmd(ONE_NM, 0.05))  # within the feedback timeout
    assert rules(feed(checker, wheel_cmd(ONE_NM, 0.2))) == [('wheel', 'injected_offline')]
    checker.note_fault('wheel', 'offline', 0.3, active=False)
    found = feed(checker, wheel_fb(0.31), wheel_cmd(ONE_NM, 0.311))
    assert rules(found) == [('wheel', 'injected_offline')]
    assert feed(checker, wheel_fb(1.31), wheel_cmd(ONE_NM, 1.311)) == []


def test_an_outage_shorter_than_the_feedback_timeout_obliges_nothing():
    checker = WireChecker(CONFIG, grace_s=0.002)
    feed(checker, wheel_fb(0.0))
    checker.note_fault('wheel', 'offline', 0.0)
    checker.note_fault('wheel', 'offline', 0.05, active=False)
    assert feed(checker, wheel_fb(0.06), wheel_cmd(ONE_NM, 0.061)) == []


def test_a_damiao_fault_state_requires_zero():
    checker = WireChecker(CONFIG)
    feed(checker, arm_fb(0.0, state=damiao.DmState.MOS_OVER_TEMPERATURE))
    found = feed(checker, arm_cmd(0.01, position=0.1, kp=5.0))
    assert rules(found) == [('arm', 'device_fault')]


def command(names, mode=1, effort=0.5, stamp=None):
    n = len(names)
    header = SimpleNamespace(stamp=SimpleNamespace(sec=0, nanosec=0))
    if stamp is not None:
        header.stamp = SimpleNamespace(sec=int(stamp), nanosec=round((stamp % 1) * 1e9))
    return SimpleNamespace(
        header=header,
        name=list(names),
        mode=[mode] * n,
        position=[0.0] * n,
        velocity=[0.0] * n,
        effort=[effort] * n,
        kp=[0.0] * n,
        kd=[0.0] * n,
    )


def test_without_a_fresh_valid_command_non_zero_is_flagged():
    checker = WireChecker(CONFIG, track_commands=True, grace_s=0.002)
    feed(checker, wheel_fb(0.0))
    checker.note_command(command(['wheel']), 0.0)
    assert feed(checker, wheel_fb(0.05), wheel_cmd(ONE_NM, 0.05)) == []
    # invalid and stale commands do not refresh it
    checker.note_command(command(['wheel'], effort=math.nan), 0.06)
    checker.note_command(command(['wheel'], mode=9), 0.06)
    checker.note_command(command(['wheel'], stamp=1.0), 1000.0)  # 999 s old
    found = feed(checker, wheel_fb(0.103), wheel_cmd(ONE_NM, 0.103))
    assert rules(found) == [('wheel', 'no_command')]
    # MODE_OFF ends the command at once (plus grace)
    checker.note_command(command(['wheel']), 0.2)
    checker.note_command(command(['wheel'], mode=0), 0.21)
    assert feed(checker, wheel_fb(0.211), wheel_cmd(ONE_NM, 0.211)) == []
    assert rules(feed(checker, wheel_fb(0.22), wheel_cmd(ONE_NM, 0.22))) == [
        ('wheel', 'no_command')
    ]


def test_a_command_frame_of_the_wrong_length_is_malformed():
    checker = WireChecker(CONFIG)
    assert rules(feed(checker, frame(0x200, b'\x00\x01', 0.0))) == [('', 'malformed')]


def test_actuator_states_with_nan_or_beyond_the_limit_are_reported():
    limits = max_efforts(CONFIG)
    assert limits == {'wheel': 1.0, 'yaw': 1.2, 'arm': 10.0}
    msg = SimpleNamespace(
        name=['wheel', 'yaw', 'arm'], mode=[1, 0, 4], command=[math.nan, 0.5, 10.5]
    )
    assert check_actuator_states(msg, limits) == [
        'wheel: command nan',
        'yaw: MODE_OFF with command +0.5000',
        'arm: command +10.5000 beyond 10.0',
    ]


def test_a_voltage_frame_sent_after_a_stall_is_judged_with_the_speeds_of_its_decision():
    checker = WireChecker(CONFIG, grace_s=0.002, stall_s=0.02, feedback_window_s=0.15)
    # the yaw turns at 300 rpm (31 rad/s, a 22.5 V back-EMF): 24 V asks ~0.6 N·m
    for k in range(50):
        t = k * MS
        feed(checker, yaw_fb(t, rpm=300), frame(0x1FF, dji.pack_command([25000]), t))
    # the bridge's process stalls after deciding a tick at 50 ms, while the motor, on its
    # own, brakes to 0 rpm and reports it for 300 ms; the 24 V frame goes out at 350 ms
    for k in range(300):
        feed(checker, yaw_fb(0.05 + k * MS, rpm=0))
    found = feed(checker, frame(0x1FF, dji.pack_command([25000]), 0.35))
    assert found == []  # decided at 300 rpm, which the speeds of 0.35 s alone would not say
    assert checker.stalls == 1
    # the next frame is decided after the stall, at rest: 24 V is 9.9 N·m
    found = feed(checker, yaw_fb(0.351), frame(0x1FF, dji.pack_command([25000]), 0.351))
    assert rules(found) == [('yaw', 'effort')]


def test_a_frame_sent_after_a_stall_is_judged_when_it_was_decided():
    checker = WireChecker(CONFIG, grace_s=0.002, stall_s=0.02)
    for k in range(50):  # a steady 1 kHz stream with fresh feedback
        t = k * MS
        feed(checker, wheel_fb(t), wheel_cmd(ONE_NM, t))
    # the process stalls 150 ms after deciding a tick at 50 ms; its frame goes out at
    # 199 ms: judged at 50 ms + 1 tick (feedback then 1 ms old), not as 150 ms offline
    assert feed(checker, wheel_cmd(ONE_NM, 0.199)) == []
    assert checker.stalls == 1 and checker.max_stall_ms == pytest.approx(150.0)
    # the next tick is decided after the stall: it must be zero (offline by then)
    found = feed(checker, wheel_cmd(ONE_NM, 0.200))
    assert rules(found) == [('wheel', 'offline')]


@given(
    st.lists(
        st.tuples(st.floats(0.0001, 0.05), st.floats(-100.0, 100.0, allow_nan=False)),
        min_size=1,
        max_size=300,
    ),
    st.floats(0.0, 3.0),
)
def test_the_sliding_window_is_the_min_and_max_of_its_samples(steps, since_back):
    """Against a brute-force reference: the samples of the last span (at least two), and
    with since, every kept sample from then on."""
    span = 0.1
    window = _Window(span)
    t, samples = 0.0, []
    for dt, x in steps:
        t += dt
        window.add(t, x)
        samples.append((t, x))
        recent = [v for tv, v in samples if tv >= t - span]
        if len(recent) < 2:
            recent = [v for _, v in samples[-2:]]
        assert window.bounds() == (min(recent), max(recent))
        assert window.last == x
    since = t - since_back
    kept = [v for tv, v in samples if tv >= max(since, t - span - _Window.HISTORY_S)]
    assert window.bounds(since) == (min(recent + kept), max(recent + kept))
