"""LK-TECH MF/MG motors: the protocol's vectors, the actuator's frames, the simulated motor."""

import math

import can
import pytest
from rm_base.hardware.actuators import Mode
from rm_base.hardware.actuators.base import HoldReason
from rm_base.hardware.errors import FrameLengthError, HardwareConfigError, ValueRangeError
from rm_base.motors import actuator_class, sim_family
from rm_base.motors.family import DeviceParts
from rm_base.motors.lk import protocol as lk
from rm_base.sim_devices.motor import MotorModel
from support.hardware import MS, T0, joint

MG, MF, V23 = lk.CURRENT_SCALES['mg'], lk.CURRENT_SCALES['mf'], lk.CURRENT_SCALES['v2.3']


# --- the protocol: docs/PROTOCOLS.md §2.8's worked vectors (motor id 1, 0x141) ---
@pytest.mark.parametrize(('data', 'hex_'), [
    (lk.pack_torque(1000, MG), 'A1 00 00 00 E8 03 00 00'),
    (lk.pack_speed(9000), 'A2 00 00 00 28 23 00 00'),
    (lk.pack_multi_turn(36000, max_dps=500), 'A4 00 F4 01 A0 8C 00 00'),
    (lk.pack_single_turn(9000, ccw=True, max_dps=360), 'A6 01 68 01 28 23 00 00'),
    (lk.pack_multi_torque((100, -100, 0, 2000)), '64 00 9C FF 00 00 D0 07'),
    (lk.pack_simple(lk.Command.READ_STATUS_1), '9A 00 00 00 00 00 00 00'),
    (lk.pack_simple(lk.Command.RUN), '88 00 00 00 00 00 00 00'),
    (lk.pack_multi_turn(-36000), 'A3 00 00 00 60 73 FF FF'),
    (lk.pack_increment(4500, max_dps=100), 'A8 00 64 00 94 11 00 00'),
])
def test_requests_are_the_vendors_bytes(data, hex_):
    assert data == bytes.fromhex(hex_)


def test_a_motion_reply_decodes_to_temperature_iq_speed_and_encoder():
    reply = lk.decode_motion_reply(bytes.fromhex('A1 28 E8 03 5A 00 00 20'))
    assert reply == lk.MotionReply(0xA1, 40, 1000, 90, 8192)
    assert 1000 * MF.reply_amps == pytest.approx(8.057, abs=1e-3)
    assert 1000 * MG.reply_amps == pytest.approx(16.113, abs=1e-3)
    assert 1000 * V23.command_amps == pytest.approx(16.0)
    assert lk.encode_motion_reply(lk.Command.TORQUE, 40, 1000, 90, 8192) == bytes.fromhex(
        'A1 28 E8 03 5A 00 00 20')


def test_status_1_reads_the_v2_35_layout():
    status = lk.decode_status_1(bytes.fromhex('9A 28 A4 10 00 00 00 01'))
    assert status.temperature_c == 40 and status.voltage_v == pytest.approx(42.60)
    assert status.current_a == 0.0 and status.motor_on
    assert status.error == lk.ErrorState.UNDER_VOLTAGE
    assert lk.encode_status_1(lk.Command.READ_STATUS_1, 40, 42.6, 0.0, motor_on=True,
                              error=1) == bytes.fromhex(
        '9A 28 A4 10 00 00 00 01')


def test_error_bits_in_words():
    assert lk.error_names(0) == 'none'
    assert lk.error_names(0x09) == 'UNDER_VOLTAGE|OVER_TEMPERATURE'
    assert lk.error_names(0x48) == 'OVER_TEMPERATURE|0x40'


def test_torque_saturates_at_the_scales_range():
    assert lk.unpack_request(lk.pack_torque(99_999, V23)).value == 2000
    assert lk.unpack_request(lk.pack_torque(-99_999, MG)).value == -2048


@pytest.mark.parametrize(('call', 'error'), [
    (lambda: lk.decode_motion_reply(bytes(7)), FrameLengthError),
    (lambda: lk.decode_motion_reply(bytes.fromhex('9A 28 A4 10 00 00 00 01')), ValueRangeError),
    (lambda: lk.decode_status_1(bytes.fromhex('A1 28 E8 03 5A 00 00 20')), ValueRangeError),
    (lambda: lk.unpack_request(bytes.fromhex('77 00 00 00 00 00 00 00')), ValueRangeError),
    (lambda: lk.pack_simple(lk.Command.TORQUE), ValueRangeError),
    (lambda: lk.pack_single_turn(36000, ccw=False), ValueRangeError),
    (lambda: lk.pack_speed(2**31), ValueRangeError),
    (lambda: lk.motor_frame_id(33), ValueRangeError),
    (lambda: lk.motor_frame_id(0), ValueRangeError),
])
def test_bad_frames_and_values_are_refused(call, error):
    with pytest.raises(error):
        call()


def test_every_request_round_trips_through_the_motors_reading():
    assert lk.unpack_request(lk.pack_multi_turn(-123456, max_dps=700)) == lk.Request(
        lk.Command.MULTI_TURN_LIMITED, -123456, 700, False)
    assert lk.unpack_request(lk.pack_single_turn(35999, ccw=False)) == lk.Request(
        lk.Command.SINGLE_TURN, 35999, None, False)
    assert lk.unpack_request(lk.pack_torque(-7, MF)) == lk.Request(
        lk.Command.TORQUE, -7, None, False)


# --- the actuator ---
def make(type_='mf9025', **extra):
    cfg = joint(type=type_, **extra)
    return actuator_class(cfg.type)(cfg)


def reply(actuator, data, now_ns):
    msg = can.Message(arbitration_id=actuator.command_id, data=data, is_extended_id=False)
    assert actuator.handle_frame(msg, now_ns)


def motion(iq=0, speed_dps=0, encoder=0, temperature=30):
    return lk.encode_motion_reply(lk.Command.TORQUE, temperature, iq, speed_dps, encoder)


def status(motor_on, error):
    return lk.encode_status_1(lk.Command.READ_STATUS_1, 40, 24.0, 0.0, motor_on=motor_on,
                              error=error)


def ticks(actuator, start_ns, n):
    """Run n 1 ms ticks with fresh feedback each; the frames sent."""
    frames = []
    for k in range(n):
        now = start_ns + k * MS
        reply(actuator, motion(), now)
        actuator.update(now, 0.001)
        frames.append(actuator.pack_command())
    return frames


def test_the_reply_becomes_the_joints_position_speed_effort_and_temperature():
    a = make('mg4010', id=3)
    assert a.command_id == 0x143 and a.feedback_ids() == (0x143,)
    reply(a, motion(iq=1000, speed_dps=900, encoder=16384, temperature=41), T0)
    fb = a.feedback
    assert fb.position == pytest.approx(2 * math.pi * 0.25 / 10.0)  # a quarter rotor turn
    assert fb.velocity == pytest.approx(math.radians(900) / 10.0)
    assert fb.effort == pytest.approx(1000 * MG.reply_amps * 0.7)
    assert fb.temperature == 41.0


def test_an_effort_is_sent_as_iq_on_0xa1():
    a = make('mf9025', id=1, max_effort=3.0)
    reply(a, motion(), T0)
    a.set_command(Mode.EFFORT, effort=1.0, now_ns=T0)
    frame = ticks(a, T0, 2)[1]  # (the first tick reads the status)
    request = lk.unpack_request(frame.data)
    assert frame.arbitration_id == 0x141 and request.command is lk.Command.TORQUE
    assert request.value == round(1.0 / 0.32 / MF.command_amps)
    assert a.effort_out == pytest.approx(1.0, abs=MF.command_amps * 0.32)


def test_a_status_read_takes_one_tick_in_status_period():
    a = make('mf9025', status_period=0.05)
    a.set_command(Mode.EFFORT, effort=0.5, now_ns=T0)
    frames = ticks(a, T0, 120)
    reads = [k for k, f in enumerate(frames) if f.data[0] == lk.Command.READ_STATUS_1]
    assert reads == [0, 50, 100]
    assert all(f.data[0] == lk.Command.TORQUE for k, f in enumerate(frames) if k not in reads)


def test_a_step_to_zero_output_is_never_delayed_by_a_status_read():
    a = make('mf9025', status_period=0.05)
    a.set_command(Mode.EFFORT, effort=0.5, now_ns=T0)
    ticks(a, T0, 50)  # the next read is due at tick 50
    a.set_command(Mode.OFF, now_ns=T0 + 50 * MS)
    frames = ticks(a, T0 + 50 * MS, 2)
    assert lk.unpack_request(frames[0].data) == lk.Request(lk.Command.TORQUE, 0, None, False)
    assert frames[1].data[0] == lk.Command.READ_STATUS_1


def test_error_bits_hold_the_joint_until_the_motor_reports_none_for_long_enough():
    a = make('mf9025')
    a.set_command(Mode.EFFORT, effort=0.5, now_ns=T0)
    ticks(a, T0, 5)
    reply(a, lk.encode_status_1(lk.Command.READ_STATUS_1, 90, 24.0, 1.0, motor_on=True,
                                error=lk.ErrorState.OVER_TEMPERATURE), T0 + 5 * MS)
    frames = ticks(a, T0 + 5 * MS, 5)
    assert a.hold_reason is HoldReason.DEVICE_FAULT
    assert all(lk.unpack_request(f.data).value == 0 for f in frames
               if f.data[0] == lk.Command.TORQUE)
    assert 'OVER_TEMPERATURE' in a.details()['lk_error']
    reply(a, status(motor_on=True, error=0), T0 + 10 * MS)
    ticks(a, T0 + 10 * MS, 2)
    assert a.hold_reason is HoldReason.DEVICE_FAULT  # one clean frame clears nothing
    a.set_command(Mode.EFFORT, effort=0.5, now_ns=T0 + 2000 * MS)
    ticks(a, T0 + 10 * MS, 2000)
    assert a.hold_reason is HoldReason.NONE


def test_a_motor_that_says_it_is_off_is_sent_run_and_stop_at_shutdown():
    a = make('mf9025')
    reply(a, status(motor_on=False, error=0), T0)
    frames = ticks(a, T0, 150)
    runs = [k for k, f in enumerate(frames) if f.data[0] == lk.Command.RUN]
    assert runs == [0, 100]  # at most every 100 ms while it says off
    assert [f.data[0] for f in a.final_frames()] == [lk.Command.STOP]


@pytest.mark.parametrize(('extra', 'words'), [
    ({'type': 'lk'}, 'needs model'),
    ({'type': 'lk', 'current_scale': 'mf'}, 'without a model, set'),
    ({'type': 'lk', 'model': 'MX100'}, 'MF9025'),
    ({'type': 'mf9025', 'id': 33}, 'outside 1..32'),
    ({'type': 'mf9025', 'current_scale': 'mx'}, 'current_scale'),
])
def test_a_config_it_cannot_drive_is_refused_with_the_key(extra, words):
    extra = dict(extra)
    with pytest.raises(HardwareConfigError, match=words):
        make(extra.pop('type'), **extra)


def test_a_generic_lk_joint_with_its_own_constants():
    a = make('lk', current_scale='v2.3', gear_ratio=6.0, torque_constant=1.2, max_effort=10.0,
             max_velocity=20.0, encoder_bits=14)
    assert a.scale is V23 and a.gear_ratio == 6.0
    reply(a, motion(encoder=8192), T0)
    assert a.feedback.position == pytest.approx(math.pi / 6.0)


# --- the simulated motor ---
def device(sim_type='mf9025', **values):
    family = sim_family(sim_type)
    values = family.schema.read('test', values, ValueError)
    model = MotorModel(family.models[sim_type])
    return family.build(values, DeviceParts('m', sim_type, 1, model, {}))


def run(dev, request, ms):
    """Send a request, then run the physics for ms; the reply."""
    [(frame_id, data)] = dev.receive(0x141, request, T0)
    assert frame_id == 0x141
    for _ in range(ms):
        dev.control(T0, 0.001)
        dev.step(0.001)
    return data


def test_the_simulated_motor_turns_on_torque_and_answers_with_its_state():
    dev = device()
    run(dev, lk.pack_torque(1000, MF), 1)  # (before the back-EMF limits it)
    assert dev.model.current == pytest.approx(1000 * MF.command_amps, rel=1e-6)
    answer = lk.decode_motion_reply(run(dev, lk.pack_simple(lk.Command.READ_STATUS_2), 0))
    assert answer.iq == 1000 and answer.speed_dps > 0


def test_the_simulated_motors_own_loops_reach_speed_and_position():
    dev = device('mg4010')
    run(dev, lk.pack_speed(round(math.degrees(5.0) * 10 * 100)), 500)  # 5 rad/s at the output
    assert dev.model.velocity == pytest.approx(5.0, rel=0.02)
    run(dev, lk.pack_multi_turn(round(math.degrees(1.0) * 10 * 100), max_dps=3000), 2000)
    assert dev.model.angle == pytest.approx(1.0, abs=0.01)


def test_off_stop_and_run_and_the_status_it_reports():
    dev = device()
    run(dev, lk.pack_torque(500, MF), 10)
    assert run(dev, lk.pack_simple(lk.Command.STOP), 10)[0] == lk.Command.STOP
    assert dev.model.current == 0.0
    assert not lk.decode_status_1(run(dev, lk.pack_simple(lk.Command.READ_STATUS_1), 0)).motor_on
    run(dev, lk.pack_simple(lk.Command.RUN), 0)
    run(dev, lk.pack_torque(500, MF), 10)
    assert dev.model.current > 0.0
    dev.supply_voltage = 15.0
    run(dev, lk.pack_torque(500, MF), 1)
    status = lk.decode_status_1(run(dev, lk.pack_simple(lk.Command.READ_STATUS_1), 0))
    assert status.error == lk.ErrorState.UNDER_VOLTAGE and dev.model.current == 0.0
    assert status.voltage_v == pytest.approx(15.0)


def test_a_malformed_request_is_ignored_and_counted():
    dev = device()
    assert dev.receive(0x141, bytes.fromhex('77 00 00 00 00 00 00 00'), T0) == []
    assert dev.receive(0x141, bytes(3), T0) == []
    assert dev.stats.ignored_frames == 2
