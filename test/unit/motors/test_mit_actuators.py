"""Damiao, Cheetah and Piper actuators: decode -> SI, native MIT passthrough, system frames."""

import math

import can
import pytest
from rm_base.hardware.actuators import Mode
from rm_base.hardware.actuators.mit import fit_mit_target
from rm_base.hardware.errors import HardwareConfigError, ValueRangeError
from rm_base.hardware.protocols import mit
from rm_base.hardware.protocols.mit import MitCommand, SystemCommand
from rm_base.motors import actuator_class
from rm_base.motors.cheetah import protocol as cheetah
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.piper import protocol as piper
from support.hardware import MS, T0, joint

DM4310 = damiao.dm_limits('DM4310')


def make(type_='dm4310', **extra):
    cfg = joint(type=type_, **extra)
    return actuator_class(cfg.type)(cfg)


def dm_frame(
    motor_id=1,
    state=1,
    position=0.0,
    velocity=0.0,
    torque=0.0,
    t_mos=30,
    t_rotor=35,
    master_id=0,
    limits=DM4310,
):
    data = damiao.encode_feedback(
        motor_id,
        state,
        position=position,
        velocity=velocity,
        torque=torque,
        t_mos=t_mos,
        t_rotor=t_rotor,
        limits=limits,
    )
    return can.Message(arbitration_id=master_id, data=data, is_extended_id=False)


def fields(msg, limits=DM4310):
    return mit.unpack_mit_command(msg.data, limits)


# --- Damiao feedback ---
def test_damiao_feedback_to_joint_si_with_gear_and_direction():
    a = make(gear_ratio=2.0, direction=-1, zero_offset=0.5, master_id=0x11)
    assert a.feedback_ids() == (0x11,)
    assert a.handle_frame(dm_frame(position=3.0, velocity=4.0, torque=2.0, master_id=0x11), T0)
    fb = a.feedback
    # encoded on the 16/12-bit grid, so compare to a step: p 25/65535, v 60/4095, t 20/4095
    assert fb.position == pytest.approx(-(3.0 / 2 - 0.5), abs=25 / 65535)
    assert fb.velocity == pytest.approx(-4.0 / 2, abs=60 / 4095)
    assert fb.effort == pytest.approx(-2.0 * 2, abs=2 * 20 / 4095)
    assert fb.temperature == 35.0  # max(MOS 30, rotor 35)


def test_damiao_matches_by_id_nibble_on_a_shared_master_id():
    a = make(id=1)
    b = make(name='k', id=2)
    frame = dm_frame(motor_id=2)
    assert not a.handle_frame(frame, T0)
    assert b.handle_frame(frame, T0)


def test_damiao_position_is_unwrapped_across_pmax():
    a = make()
    a.handle_frame(dm_frame(position=12.4), T0)
    a.handle_frame(dm_frame(position=-12.4), T0 + MS)  # wrapped: +0.2 rad, not -24.8
    assert a.feedback.position == pytest.approx(12.6, abs=1e-3)


def test_damiao_fault_state_is_reported_and_holds_zero():
    a = make()
    a.handle_frame(dm_frame(state=damiao.DmState.OVER_CURRENT), T0)
    a.set_command(Mode.EFFORT, T0, effort=1.0)
    a.update(T0, 0.001)
    assert a.state().error_code == 0xA
    assert a.state().mode == Mode.OFF
    assert a.mit_fields == MitCommand(0, 0, 0, 0, 0)
    # enabled / disabled are states, not errors
    a.handle_frame(dm_frame(state=damiao.DmState.ENABLED), T0 + MS)
    assert a.feedback.error_code == 0


def test_damiao_model_from_option_and_limit_overrides():
    a = make('damiao', model='DM8009', limits={'v_max': 30.0})
    assert (a.limits.p_max, a.limits.v_max, a.limits.t_max) == (12.5, 30.0, 54.0)
    assert a.max_effort == 54.0
    with pytest.raises(HardwareConfigError, match='model is required'):
        make('damiao')
    with pytest.raises(HardwareConfigError, match="unknown Damiao model 'DM9'"):
        make('damiao', model='DM9')
    with pytest.raises(HardwareConfigError, match='unknown MIT limit'):
        make(limits={'vmax': 1.0})


@pytest.mark.parametrize(
    ('options', 'message'),
    [
        ({'auto_enable': 'false'}, r"joints\.j\.auto_enable must be bool; got str 'false'"),
        ({'disable_on_shutdown': 0}, r'joints\.j\.disable_on_shutdown must be bool'),
        ({'master_id': 0x800}, r'joints\.j\.master_id must be <= 2047, got 2048'),
        ({'limits': [1, 2]}, r'joints\.j\.limits must be mapping'),
        ({'limits': {'v_max': 'fast'}}, r'joints\.j\.limits: MIT limit v_max must be a number'),
        ({'mode': 'mit'}, r"joints\.j: unknown key\(s\) \['mode'\]"),
    ],
)
def test_a_bad_mit_option_is_refused_naming_its_key(options, message):
    with pytest.raises(HardwareConfigError, match=message):
        make(**options)


# --- commands ---
def ticked(a, now_ns=T0, **command):
    a.set_command(now_ns=now_ns, **command)
    a.update(now_ns, 0.001)
    return a.pack_command()


def online(a, now_ns=T0, **fb):
    a.handle_frame(dm_frame(**fb), now_ns)


def test_first_frame_is_enable_then_commands():
    a = make()
    online(a)
    first = ticked(a, mode=Mode.EFFORT, effort=1.0)
    assert (first.arbitration_id, bytes(first.data)) == (
        0x001,
        mit.system_frame(SystemCommand.ENABLE),
    )
    second = a.pack_command()
    assert fields(second).torque == pytest.approx(1.0, abs=20 / 4095)
    assert fields(second).kp == 0.0


def test_mit_mode_is_passed_through_natively():
    a = make(auto_enable=False)
    online(a, position=0.2)
    msg = ticked(a, mode=Mode.MIT, position=0.5, velocity=1.0, effort=0.3, kp=5.0, kd=0.2)
    f = fields(msg)
    assert f.position == pytest.approx(0.5, abs=25 / 65535)
    assert f.velocity == pytest.approx(1.0, abs=60 / 4095)
    assert f.kp == pytest.approx(5.0, abs=500 / 4095)
    assert f.kd == pytest.approx(0.2, abs=5 / 4095)
    assert f.torque == pytest.approx(0.3, abs=20 / 4095)
    # reported command: host estimate 5*(0.5-0.2) + 0.2*(1-0) + 0.3 = 2.0 N·m
    assert a.state().command == pytest.approx(2.0, abs=2e-3)


def test_mit_passthrough_with_gear_and_direction_converts_to_the_motor_side():
    a = make(auto_enable=False, gear_ratio=2.0, direction=-1)
    online(a)
    f = fields(ticked(a, mode=Mode.MIT, position=0.5, velocity=1.0, effort=0.4, kp=8.0, kd=0.4))
    # p_dev = 2 * (-1 * 0.5) = -1; v_dev = -2; kp/4 = 2; kd/4 = 0.1; tau_dev = -0.4/2 = -0.2
    assert (f.position, f.velocity) == pytest.approx((-1.0, -2.0), abs=0.02)
    assert (f.kp, f.kd, f.torque) == pytest.approx((2.0, 0.1, -0.2), abs=0.13)


def test_mit_passthrough_is_limited_to_max_effort_by_moving_the_target():
    a = make(auto_enable=False, max_effort=2.0)
    online(a, position=0.0)
    f = fields(ticked(a, mode=Mode.MIT, position=1.0, kp=100.0))
    # 100 * (1 - 0) = 100 N·m > 2 -> target moved to 0.02 rad so 100 * 0.02 = 2 N·m
    assert f.position == pytest.approx(0.02, abs=25 / 65535)
    assert a.state().command == pytest.approx(2.0)


def test_held_damiao_gets_a_limp_zero_frame():
    a = make(auto_enable=False)
    msg = ticked(a, mode=Mode.EFFORT, effort=1.0)  # no feedback yet: offline
    assert bytes(msg.data) == mit.pack_mit_command(MitCommand(0, 0, 0, 0, 0), DM4310)


def test_auto_enable_when_the_motor_reports_disabled_at_most_every_100_ms():
    a = make()
    online(a, state=damiao.DmState.DISABLED)
    assert ticked(a, mode=Mode.OFF).data[7] == SystemCommand.ENABLE  # start-up enable
    for k in range(1, 100):
        now = T0 + k * MS
        online(a, now, state=damiao.DmState.DISABLED)
        ticked(a, now, mode=Mode.OFF)
        assert a.system_frames_sent == 1, k
    now = T0 + 100 * MS
    online(a, now, state=damiao.DmState.DISABLED)
    assert ticked(a, now, mode=Mode.OFF).data[7] == SystemCommand.ENABLE
    assert a.system_frames_sent == 2


def test_requested_system_command_replaces_one_command_frame():
    a = make(auto_enable=False)
    online(a)
    a.request_system_command(SystemCommand.CLEAR_ERROR)
    msg = ticked(a, mode=Mode.OFF)
    assert bytes(msg.data) == mit.system_frame(SystemCommand.CLEAR_ERROR)
    assert a.pack_command().data[:7] != b'\xff' * 7
    assert bytes(a.final_frames()[0].data) == mit.system_frame(SystemCommand.DISABLE)


# --- Cheetah ---
def test_cheetah_reply_and_no_clear_error():
    a = make('cheetah', id=3, auto_enable=False)
    reply = cheetah.encode_reply(3, position=1.0, velocity=-2.0, torque=0.5)
    assert a.handle_frame(can.Message(arbitration_id=0, data=reply, is_extended_id=False), T0)
    assert a.feedback.position == pytest.approx(1.0, abs=25 / 65535)
    assert a.feedback.velocity == pytest.approx(-2.0, abs=130 / 4095)
    assert math.isnan(a.state().temperature)
    other = cheetah.encode_reply(4, position=0.0, velocity=0.0, torque=0.0)
    assert not a.handle_frame(can.Message(arbitration_id=0, data=other), T0)
    with pytest.raises(ValueRangeError, match='no clear-error'):
        a.request_system_command(SystemCommand.CLEAR_ERROR)
    a.request_system_command(SystemCommand.SET_ZERO)
    a.update(T0, 0.001)
    assert a.pack_command().data[7] == SystemCommand.SET_ZERO


def test_cheetah_enables_again_when_it_comes_back_online():
    a = make('cheetah', id=3)
    a.update(T0, 0.001)
    assert a.pack_command().data[7] == SystemCommand.ENABLE
    reply = can.Message(
        arbitration_id=0, data=cheetah.encode_reply(3, position=0.0, velocity=0.0, torque=0.0)
    )
    a.handle_frame(reply, T0 + 200 * MS)
    a.update(T0 + 200 * MS, 0.001)
    assert a.pack_command().data[7] == SystemCommand.ENABLE
    assert a.system_frames_sent == 2


# --- Piper ---
def piper_feedback(a, now_ns, angle, velocity, current):
    can_id, data = piper.encode_joint_feedback(
        1, angle if a.joint == 1 else 0.0, angle if a.joint == 2 else 0.0
    )
    a.handle_frame(can.Message(arbitration_id=can_id, data=data), now_ns)
    can_id, data = piper.encode_high_speed_feedback(a.joint, velocity, current)
    a.handle_frame(can.Message(arbitration_id=can_id, data=data), now_ns)


def test_piper_joint_state_and_native_mit():
    a = make('piper', id=2)
    assert a.feedback_ids() == (0x2A5, 0x252)
    piper_feedback(a, T0, math.radians(30.0), 0.5, 2.0)
    assert a.feedback.position == pytest.approx(math.radians(30.0))
    assert a.feedback.velocity == pytest.approx(0.5)
    assert a.feedback.effort == pytest.approx(2.0 * 1.18125)  # SDK coefficient, joints 1-3
    a.set_command(Mode.MIT, T0, position=0.6, velocity=0.0, effort=0.0, kp=10.0, kd=0.8)
    a.update(T0, 0.001)
    msg = a.pack_command()
    assert msg.arbitration_id == 0x15B
    joint_no, cmd = piper.unpack_joint_mit(msg.arbitration_id, msg.data)
    assert joint_no == 2
    assert cmd.position == pytest.approx(0.6, abs=25 / 65535)
    assert cmd.kp == pytest.approx(10.0, abs=500 / 4095)


def test_piper_rejects_bad_joint_ids_and_gears():
    with pytest.raises(HardwareConfigError, match=r'Piper joint 1\.\.6'):
        make('piper', id=7)
    with pytest.raises(HardwareConfigError, match='Piper joints are 1:1'):
        make('piper', id=1, gear_ratio=2.0)


@pytest.mark.parametrize(
    ('kp', 'kd', 'moved'),
    [(10.0, 1.0, 'position'), (0.0, 2.0, 'velocity'), (0.0, 0.0, 'feed-forward')],
)
def test_an_mit_target_is_moved_so_the_motor_law_gives_the_effort(kp, kd, moved):
    p, v, ff = fit_mit_target(kp, kd, 1.0, 3.0, 0.5, q=0.2, dq=-1.0, effort=2.0)
    assert kp * (p - 0.2) + kd * (v + 1.0) + ff == pytest.approx(2.0)
    changed = {'position': p != 1.0, 'velocity': v != 3.0, 'feed-forward': ff != 0.5}
    assert [name for name, c in changed.items() if c] == [moved]


def test_piper_encodes_torque_over_18_nm_unless_told_8():
    # 2 N·m on the 8-bit field, truncated as the SDK's float_to_uint does: (2 + 18) / 36 *
    # 255 = 141.7 -> 141 over ±18, or (2 + 8) / 16 * 255 = 159.4 -> 159 over ±8 (the
    # firmware's range is not known here: ±18 read as ±8 is 0.44 x the torque, never more)
    for options, t_max, raw in (({}, 18.0, 141), ({'torque_range': 8}, 8.0, 159)):
        a = make('piper', id=1, **options)
        assert a.limits.t_max == t_max
        # the encoding it assumes is on the joint's /diagnostics
        assert a.diagnostics()['details'] == {'torque_range [N*m]': t_max}
        piper_feedback(a, T0, 0.0, 0.0, 0.0)
        a.set_command(Mode.MIT, T0, position=0.0, velocity=0.0, effort=2.0, kp=0.0, kd=0.0)
        a.update(T0, 0.001)
        msg = a.pack_command()
        raw_torque = ((msg.data[6] & 0x0F) << 4) | (msg.data[7] >> 4)
        assert raw_torque == raw, (options, raw_torque)


@pytest.mark.parametrize('value', [10, True, 'eighteen', 18.5])
def test_piper_refuses_a_torque_range_no_firmware_has(value):
    message = r'joints\.j\.torque_range must be one of 18, 8, got'
    with pytest.raises(HardwareConfigError, match=message):
        make('piper', id=1, torque_range=value)
