"""DJI actuators: feedback -> joint SI, control modes, clamping."""

import math
import random

import can
import pytest
from rm_base.hardware.actuators import HoldReason, Mode
from rm_base.hardware.errors import HardwareConfigError
from rm_base.motors import actuator_class
from rm_base.motors.dji import protocol as dji
from support.hardware import MS, T0, joint
from support.hardware import feed_dji as feed

M3508_GEAR = 3591 / 187


def make(type_='m3508', **extra):
    cfg = joint(type=type_, **extra)
    return actuator_class(cfg.type)(cfg)


# --- feedback -> SI ---
def test_m3508_feedback_is_converted_to_the_output_shaft():
    a = make()
    feed(a, T0, ticks=4096, rpm=1000, current=1000, temperature=40)
    fb = a.feedback
    # rotor pi rad / (3591/187) = 0.163597 rad
    assert fb.position == pytest.approx(math.pi / M3508_GEAR)
    # 1000 rpm rotor = 104.72 rad/s / 19.2032 = 5.45329 rad/s at the output
    assert fb.velocity == pytest.approx(1000 * 2 * math.pi / 60 / M3508_GEAR)
    # 1000 raw * 20/16384 A * 0.3 N·m/A = 0.366211 N·m (docs/PROTOCOLS.md F1, sign flipped)
    assert fb.effort == pytest.approx(0.366211, abs=1e-6)
    assert fb.temperature == 40


def test_direction_and_zero_offset():
    a = make(direction=-1, zero_offset=0.1)
    feed(a, T0, ticks=4096, rpm=1000, current=1000)
    # position = -1 * (0.163597 - 0.1)
    assert a.feedback.position == pytest.approx(-(math.pi / M3508_GEAR - 0.1))
    assert a.feedback.velocity == pytest.approx(-1000 * 2 * math.pi / 60 / M3508_GEAR)
    assert a.feedback.effort == pytest.approx(-0.366211, abs=1e-6)


def test_configured_gear_ratio_scales_the_default_torque_constant():
    # 3508 motor without its gearbox: ratio 1, Kt 0.3 * 1 / 19.2032 = 0.015622 N·m/A
    a = make(gear_ratio=1.0)
    assert a.torque_constant == pytest.approx(0.3 / M3508_GEAR)
    feed(a, T0, ticks=0, rpm=60, current=16384)
    assert a.feedback.velocity == pytest.approx(2 * math.pi)
    assert a.feedback.effort == pytest.approx(20 * 0.3 / M3508_GEAR)


def test_configured_gear_ratio_scales_the_default_speed_and_effort_limits():
    # The same motor without its 19.2:1 gearbox: speed limit x19.2, effort limit /19.2.
    stock, direct = make(), make(gear_ratio=1.0)
    assert direct.max_velocity == pytest.approx(stock.max_velocity * M3508_GEAR)
    assert direct.max_effort == pytest.approx(stock.max_effort / M3508_GEAR)


def test_explicit_limits_win_over_the_scaled_defaults():
    a = make(gear_ratio=1.0, max_velocity=900.0, max_effort=0.25)
    assert (a.max_velocity, a.max_effort) == (900.0, 0.25)


def test_gm6020_wraps_multi_turn_and_starts_near_zero():
    a = make('gm6020')
    # 8000 ticks = 6.1359 rad -> started within half a turn of zero: 6.1359 - 2pi = -0.14726
    feed(a, T0, ticks=8000)
    assert a.feedback.position == pytest.approx(8000 * dji.RAD_PER_TICK - 2 * math.pi)
    # 100 ticks next: +292 ticks across the wrap, not -7900
    feed(a, T0 + MS, ticks=100)
    assert a.feedback.position == pytest.approx((100 + 8192 - 8192) * dji.RAD_PER_TICK)
    # two more turns forward in steps of 4000 ticks (half a turn a frame: turning)
    t = 100
    for k in range(4):
        t = (t + 4000) % 8192
        feed(a, T0 + (2 + k) * 50 * MS, ticks=t, rpm=600)
    assert a.feedback.position == pytest.approx((100 + 16000) * dji.RAD_PER_TICK)


def test_m2006_has_no_temperature_and_reports_nan():
    a = make('m2006', id=7)
    assert a.feedback_id == 0x207
    feed(a, T0, ticks=0, rpm=10000, current=-5000, temperature=None)
    # F3: 10000 rpm / 36 = 29.0888 rad/s; -5000 raw = -5 A * 0.18 = -0.9 N·m
    assert a.feedback.velocity == pytest.approx(29.0888, abs=1e-4)
    assert a.feedback.effort == pytest.approx(-0.9)
    assert math.isnan(a.state().temperature)


def test_frames_for_other_ids_or_malformed_are_not_taken():
    a = make()
    bad = can.Message(arbitration_id=0x201, data=bytes(7), is_extended_id=False)
    assert a.handle_frame(bad, T0)  # it is ours, but malformed: counted, not used
    assert a.decode_errors == 1
    assert a.feedback is None


@pytest.mark.parametrize(
    ('type_', 'limit_rpm'),
    [
        ('gm6020', 640),  # 2 x 33.5 rad/s no-load
        ('m3508', 18_338),  # 2 x 50 rad/s x 19.2 at the rotor
        ('m2006', 35_753),  # beyond int16: every speed a C610 can send is plausible
    ],
)
def test_when_a_frame_reports_an_implausible_speed_expect_it_rejected(type_, limit_rpm):
    # No checksum on DJI frames: a corrupted one can carry any speed, which a GM6020 in
    # voltage mode would turn into a back-EMF term far beyond its torque limit.
    a = make(type_)
    assert a.max_rotor_rpm == limit_rpm
    if limit_rpm < dji.INT16_MAX:
        feed(a, T0, ticks=100, rpm=-limit_rpm, temperature=40)
        good = a.feedback
        msg = can.Message(arbitration_id=a.feedback_id, is_extended_id=False,
                          data=dji.encode_feedback(5000, limit_rpm + 1, 0, 90))
        assert a.handle_frame(msg, T0 + MS)  # ours, counted, not used
        assert a.decode_errors == 1
        assert a.feedback is good


def test_when_garbage_comes_on_a_gm6020_id_expect_the_voltage_command_within_its_limit():
    rng = random.Random(7)
    a = make('gm6020')  # voltage mode, max_effort 1.2 N·m
    limit_v = a.max_rotor_rpm * dji.RAD_PER_S_PER_RPM * a.back_emf_constant
    for k in range(2000):
        data = bytes(rng.getrandbits(8) for _ in range(8))
        a.handle_frame(can.Message(arbitration_id=a.feedback_id, data=data,
                                   is_extended_id=False), T0 + k * MS)
        fb = a.feedback
        if fb is not None:
            # every speed the actuator believes keeps the back-EMF term within twice the
            # no-load voltage
            assert abs(fb.device_velocity * a.back_emf_constant) <= limit_v
    assert a.decode_errors > 1900  # ~98 % of random frames rejected


# --- control modes ---
def run(a, mode, now_ns=T0, **fields):
    a.set_command(mode, now_ns, **fields)
    a.update(now_ns, 0.001)
    return a.command_raw


def test_effort_mode_converts_newton_metres_to_raw_current():
    a = make()
    feed(a, T0)
    # 1 N·m / 0.3 N·m/A = 3.333 A * 16384/20 = 2730.67 -> 2731
    assert run(a, Mode.EFFORT, effort=1.0) == 2731
    assert a.state().mode == Mode.EFFORT
    # the command reported is the effort of the raw actually sent: 2731 * 20/16384 * 0.3
    assert a.state().command == pytest.approx(2731 * 20 / 16384 * 0.3)


def test_effort_is_clamped_to_max_effort_and_raw_limit():
    a = make(max_effort=3.0)
    feed(a, T0)
    # 3 N·m / 0.3 = 10 A -> 8192 raw
    assert run(a, Mode.EFFORT, effort=100.0) == 8192
    assert run(a, Mode.EFFORT, effort=-100.0) == -8192
    b = make()  # default max effort 6 N·m = 20 A = the full 16384
    feed(b, T0)
    assert run(b, Mode.EFFORT, effort=1e9) == 16384


def test_direction_flips_the_command():
    a = make(direction=-1)
    feed(a, T0)
    assert run(a, Mode.EFFORT, effort=1.0) == -2731


def test_velocity_mode_runs_the_velocity_pid():
    a = make(velocity_pid={'kp': 0.5})
    feed(a, T0, rpm=0)
    # e = 2 rad/s -> 0.5 * 2 = 1 N·m -> 2731 raw
    assert run(a, Mode.VELOCITY, velocity=2.0) == 2731


def test_velocity_target_is_clamped_to_max_velocity():
    a = make(velocity_pid={'kp': 0.5}, max_velocity=1.0)
    feed(a, T0)
    # target 100 -> 1 rad/s -> 0.5 N·m -> 0.5/0.3 A * 819.2 = 1365.3 -> 1365
    assert run(a, Mode.VELOCITY, velocity=100.0) == 1365


def test_position_mode_cascades_position_into_velocity():
    a = make('gm6020_current', position_pid={'kp': 10.0}, velocity_pid={'kp': 0.5})
    feed(a, T0, ticks=0)
    # q = 0: v* = 10 * 0.1 + ff 0.2 = 1.2 rad/s; tau = 0.5 * 1.2 = 0.6 N·m
    # amps = 0.6 / 0.741 = 0.80972 A; raw = 0.80972 * 16384 / 3 = 4422.1 -> 4422
    assert run(a, Mode.POSITION, position=0.1, velocity=0.2) == 4422


def test_mit_mode_on_a_dji_motor_is_computed_on_the_host():
    a = make('gm6020_current')
    feed(a, T0, ticks=0, rpm=0)
    # tau = 2 * (0.3 - 0) + 0.1 * (1 - 0) + 0.05 = 0.75 N·m -> 0.75/0.741 A -> 5528.1 -> 5528
    assert run(a, Mode.MIT, position=0.3, velocity=1.0, effort=0.05, kp=2.0, kd=0.1) == 5528


def test_gm6020_voltage_mode_adds_back_emf():
    a = make('gm6020', resistance=2.0, back_emf_constant=0.5)
    feed(a, T0, rpm=60)  # 2pi rad/s
    # effort 0.741 N·m -> 1 A; V = 2 * 1 + 0.5 * 2pi = 5.14159 V; raw = V * 25000/24 = 5355.8
    assert run(a, Mode.EFFORT, effort=0.741) == 5356


def test_gm6020_voltage_command_is_clamped_to_25000_by_default():
    a = make('gm6020', max_effort=100.0)
    feed(a, T0)
    assert run(a, Mode.EFFORT, effort=100.0) == 25000


def test_off_mode_sends_zero():
    a = make()
    feed(a, T0)
    run(a, Mode.EFFORT, effort=1.0)
    assert run(a, Mode.OFF, effort=1.0) == 0
    assert a.hold_reason is HoldReason.OFF
    assert a.state().mode == Mode.OFF
    assert a.state().command == 0.0


def test_mode_change_resets_the_integrators():
    a = make(velocity_pid={'ki': 100.0}, position_pid={'kp': 1.0})
    feed(a, T0)
    for k in range(10):
        a.set_command(Mode.VELOCITY, T0 + k * MS, velocity=1.0)
        a.update(T0 + k * MS, 0.001)
    assert a.command_raw != 0
    # POSITION with the target at the current position: v* = 0, fresh integrator -> 0
    a.set_command(Mode.POSITION, T0 + 10 * MS, position=a.feedback.position)
    a.update(T0 + 10 * MS, 0.001)
    assert a.command_raw == 0


# --- config errors ---
def test_a_typo_of_a_joint_key_names_the_key_it_meant_and_every_key_a_joint_has():
    # The finding: max_efort was answered with the family's options only (raw_limit...)
    with pytest.raises(HardwareConfigError) as err:
        make(max_efort=2.0)
    text = str(err.value)
    assert "unknown key(s) ['max_efort'] (did you mean 'max_effort' for 'max_efort'?)" in text
    assert "'max_effort'" in text.split('allowed:')[1] and "'raw_limit'" in text


def test_unknown_option_and_bad_id_are_config_errors():
    with pytest.raises(HardwareConfigError, match=r"unknown key\(s\) \['model'\]"):
        make(model='DM4310')
    with pytest.raises(HardwareConfigError, match=r'ESC id 8 out of range 1\.\.7'):
        make('gm6020', id=8)
    with pytest.raises(HardwareConfigError, match='raw_limit 30001'):
        make('gm6020', raw_limit=30001)
    with pytest.raises(HardwareConfigError, match='resistance must be > 0'):
        make('gm6020', resistance=0.0)


def test_a_lone_corrupted_speed_does_not_drive_the_gm6020_voltage_to_its_clamp():
    # The soak's case: a frame with a legal angle and a speed inside the bound (-520 rpm)
    # on a rotor at rest. Taken as the speed, Ke*w would ask for -37 V: the -24 V clamp,
    # which drives ~13 A into a stopped rotor.
    a = make('gm6020')  # voltage mode, R 1.8, Ke 0.716, max_effort 1.2 N·m
    for k in range(3):
        feed(a, T0 + k * MS, rpm=0)
    feed(a, T0 + 3 * MS, rpm=-520)
    raw = run(a, Mode.EFFORT, T0 + 3 * MS, effort=0.5)
    # 0.5 N·m -> 0.675 A -> V = 1.8 * 0.675 = 1.21 V -> raw 1265: no back-EMF term
    assert raw == round(1.8 * 0.5 / 0.741 * 25000 / 24)
    assert a.state().command == pytest.approx(0.5, abs=0.01)


def test_the_gm6020_voltage_follows_a_real_speed_change_one_frame_late():
    a = make('gm6020', resistance=2.0, back_emf_constant=0.5)
    w = 60 * dji.RAD_PER_S_PER_RPM  # 60 rpm = 2 pi rad/s
    for k in range(3):
        feed(a, T0 + k * MS, rpm=0)
    feed(a, T0 + 3 * MS, rpm=60)
    assert a.back_emf_speed == 0.0  # one frame: could be a corrupted one
    feed(a, T0 + 4 * MS, rpm=60)
    assert a.back_emf_speed == pytest.approx(w)  # two of three: the rotor turns
    # after a gap the speeds before it are forgotten; of two frames the slower counts
    feed(a, T0 + 50 * MS, rpm=30)
    assert a.back_emf_speed == pytest.approx(w / 2)
    feed(a, T0 + 51 * MS, rpm=600)
    assert a.back_emf_speed == pytest.approx(w / 2)
