"""Physics of rm_base.sim_devices.motor: torque balance, friction, limits, encoder, heat."""

import itertools
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rm_base.sim_devices.errors import SimConfigError
from rm_base.sim_devices.motor import DJI_ENCODER_COUNTS, DriveMode, MotorModel
from rm_base.sim_devices.motor_params import MOTOR_DEFAULTS, MotorType, motor_params

DT = 1e-3


def run(model: MotorModel, seconds: float, dt: float = DT) -> None:
    for _ in range(round(seconds / dt)):
        model.step(dt)


def test_when_constant_current_expect_speed_from_torque_balance():
    # M3508 with b = 0.02 N·m·s/rad, c = 0.1 N·m, Kt = 0.3 N·m/A at the output.
    # Steady state: Kt*I = c + b*w  ->  w = (0.3*2 - 0.1) / 0.02 = 25 rad/s at the output.
    # The voltage limit is far away: (24 V - 0.45*25) / 0.194 Ω = 65.7 A > 2 A.
    # Time constant J_out / b = (1.2e-5 * (3591/187)**2) / 0.02 = 0.22 s; 3 s is > 13 of them.
    model = MotorModel(motor_params('m3508', viscous_friction=0.02))
    model.command_current(2.0)
    run(model, 3.0)
    assert model.velocity == pytest.approx(25.0, rel=1e-4)
    assert model.current == pytest.approx(2.0)
    assert model.torque == pytest.approx(0.6)


def test_when_torque_below_coulomb_friction_expect_rotor_holds():
    # 0.3 A * 0.3 N·m/A = 0.09 N·m < c = 0.1 N·m: stiction holds the rotor exactly.
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508])
    model.command_current(0.3)
    run(model, 1.0)
    assert model.velocity == 0.0
    assert model.angle == 0.0


def test_when_torque_above_coulomb_friction_expect_rotor_turns():
    # 0.4 A * 0.3 = 0.12 N·m > 0.1 N·m.
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508])
    model.command_current(0.4)
    run(model, 0.2)
    assert model.velocity > 0.0


def test_when_current_command_exceeds_limit_expect_clamped_current():
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M2006])
    model.command_current(-100.0)
    model.step(DT)
    assert model.current == pytest.approx(-10.0)


def test_when_full_voltage_expect_no_load_speed_from_back_emf():
    # GM6020 voltage mode, 24 V. Steady state: Kt*(V - Ke*w)/R = c + b*w
    #   -> w = (Kt*V/R - c) / (Kt*Ke/R + b)
    #        = (0.741*24/1.8 - 0.02) / (0.741*0.70/1.8 + 0.002) = 33.94 rad/s (~324 rpm).
    p = MOTOR_DEFAULTS[MotorType.GM6020]
    expected = (p.torque_constant * 24.0 / p.resistance - p.coulomb_friction) / (
        p.torque_constant * p.back_emf_constant / p.resistance + p.viscous_friction
    )
    model = MotorModel(p)
    model.command_voltage(24.0)
    assert model.mode is DriveMode.VOLTAGE
    run(model, 2.0)
    assert model.velocity == pytest.approx(expected, rel=1e-4)
    assert 33.0 < expected < 35.0


def test_when_current_command_at_no_load_speed_expect_voltage_limits_speed():
    # M3508 asked for 20 A with nothing to push against: the speed settles where the
    # back-EMF leaves just enough voltage for the friction current.
    # Kt*(V - Ke*w)/R = c + b*w -> w = (0.3*24/0.194 - 0.1) / (0.3*0.45/0.194 + 0.0025)
    p = MOTOR_DEFAULTS[MotorType.M3508]
    expected = (p.torque_constant * 24.0 / p.resistance - p.coulomb_friction) / (
        p.torque_constant * p.back_emf_constant / p.resistance + p.viscous_friction
    )
    model = MotorModel(p)
    model.command_current(20.0)
    run(model, 3.0)
    assert model.velocity == pytest.approx(expected, rel=1e-3)
    assert model.current < 1.0


def test_when_rotor_turns_forward_expect_encoder_wraps_8191_to_0_once_per_rotor_turn():
    model = MotorModel(motor_params('gm6020', coulomb_friction=0.0, viscous_friction=0.0))
    model.reset(velocity=2.0 * math.pi)  # one rotor turn per second (direct drive)
    counts = [model.encoder_count]
    for _ in range(2500):
        model.step(DT)
        counts.append(model.encoder_count)
    wraps = [i for i in range(1, len(counts)) if counts[i] < counts[i - 1]]
    assert len(wraps) == 2  # 2.5 rotor turns in 2.5 s
    for i in wraps:
        assert counts[i - 1] > DJI_ENCODER_COUNTS - 20 and counts[i] < 20
    assert all(0 <= c < DJI_ENCODER_COUNTS for c in counts)


def test_when_rotor_turns_backward_expect_encoder_wraps_0_to_8191():
    model = MotorModel(motor_params('gm6020', coulomb_friction=0.0, viscous_friction=0.0))
    model.reset(velocity=-2.0 * math.pi)
    counts = [model.encoder_count]
    for _ in range(1500):
        model.step(DT)
        counts.append(model.encoder_count)
    wraps = [i for i in range(1, len(counts)) if counts[i] > counts[i - 1]]
    assert len(wraps) == 2  # starts at 0, wraps at once, then once more after a turn
    for i in wraps:
        assert counts[i - 1] < 20 and counts[i] > DJI_ENCODER_COUNTS - 20


@pytest.mark.parametrize(
    ('rotor_angle', 'count'),
    [
        (0.0, 0),
        (2 * math.pi * 4095 / 8192, 4095),
        (-1e-9, 8191),
        (2 * math.pi * 3 + 2 * math.pi * 100.5 / 8192, 100),
        (-2 * math.pi * 2 - 2 * math.pi * 0.5 / 8192, 8191),
    ],
)
def test_encoder_count_is_rotor_angle_modulo_one_turn(rotor_angle, count):
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508])
    model.rotor_angle = rotor_angle
    assert model.encoder_count == count


def test_encoder_count_is_on_the_rotor_not_the_output():
    # One output turn of an M3508 is 3591/187 rotor turns: the encoder shows the fraction.
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508], angle=2 * math.pi)
    frac = 3591 / 187 - 19
    assert model.encoder_count == int(frac * 8192)


def test_when_current_flows_expect_temperature_rises_to_i2r_rth():
    # Locked M3508 at 10 A: P = I²R = 100 * 0.194 = 19.4 W; steady rise = P * R_th
    # = 19.4 * 1.5 = 29.1 K above 25 °C. Thermal time constant R_th*C = 300 s; 10 τ run.
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508])
    model.locked = True
    model.command_current(10.0)
    temps = []
    for _ in range(3000):
        model.step(1.0)
        temps.append(model.temperature)
    assert all(b >= a for a, b in itertools.pairwise(temps))
    assert model.temperature == pytest.approx(25.0 + 29.1, abs=0.01)


def test_when_current_stops_expect_temperature_cools_to_ambient():
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M2006])
    model.temperature = 80.0
    for _ in range(5000):
        model.step(1.0)  # τ = 4 K/W * 60 J/K = 240 s
    assert model.temperature == pytest.approx(25.0, abs=0.01)


def test_when_temperature_overridden_expect_held_value():
    model = MotorModel(MOTOR_DEFAULTS[MotorType.DM4310])
    model.temperature_override = 130.0
    run(model, 0.01)
    assert model.temperature == 130.0


def test_when_locked_expect_no_motion_but_current_flows():
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508])
    model.locked = True
    model.command_current(5.0)
    run(model, 0.1)
    assert model.velocity == 0.0
    assert model.angle == 0.0
    assert model.current == pytest.approx(5.0)


def test_when_brake_torque_exceeds_motor_torque_expect_hold():
    # 1 A * 0.3 = 0.3 N·m < c + brake = 0.1 + 0.5 N·m.
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508])
    model.brake_torque = 0.5
    model.command_current(1.0)
    run(model, 0.2)
    assert model.velocity == 0.0


def test_when_external_torque_expect_motor_accelerates_with_it():
    # Frictionless GM6020, 0.2 N·m load, no current: w = tau/J * t = 0.2/2e-4 * 0.01 = 10 rad/s.
    model = MotorModel(motor_params('gm6020', coulomb_friction=0.0, viscous_friction=0.0))
    model.external_torque = 0.2
    run(model, 0.01)
    assert model.velocity == pytest.approx(10.0, rel=1e-9)


def test_when_stator_accelerates_expect_free_load_keeps_world_speed():
    # Frictionless, unpowered: the load's world speed stays 0, so the relative (encoder)
    # speed is -alpha*t = -3 rad/s² * 0.5 s = -1.5 rad/s at the output.
    model = MotorModel(motor_params('m3508', coulomb_friction=0.0, viscous_friction=0.0))
    for _ in range(500):
        model.step(DT, stator_acceleration=3.0)
    assert model.velocity == pytest.approx(-1.5, rel=1e-9)


def test_when_no_input_and_no_friction_expect_energy_conserved():
    model = MotorModel(
        motor_params('dm4310', coulomb_friction=0.0, viscous_friction=0.0), velocity=5.0
    )
    energy = model.kinetic_energy
    run(model, 10.0)
    assert model.kinetic_energy == pytest.approx(energy, rel=1e-12)


def _mit_energy(model: MotorModel, kp: float) -> float:
    return model.kinetic_energy + 0.5 * kp * model.angle**2


@pytest.mark.parametrize('kd', [0.0, 5.0])
def test_when_stiff_mit_gains_expect_energy_never_grows(kd):
    # DM4310 with no load: J_out = 1.5e-5 * 10² = 1.5e-3 kg·m². kp = 500 gives
    # w_n = sqrt(500/1.5e-3) = 577 rad/s (w_n*dt = 0.58) and kd = 5 gives kd*dt/J = 3.3,
    # which explicit Euler could not take (limit 2). Energy must never grow.
    kp = 500.0
    model = MotorModel(
        motor_params('dm4310', coulomb_friction=0.0, viscous_friction=0.0), angle=0.01
    )
    model.command_impedance(0.0, 0.0, kp, kd, 0.0)
    energy = _mit_energy(model, kp)
    assert energy == pytest.approx(0.5 * 500 * 1e-4)
    for _ in range(5000):
        model.step(DT)
        new = _mit_energy(model, kp)
        assert new <= energy * (1 + 1e-12) + 1e-15
        energy = new
    assert abs(model.angle) < 0.01


@settings(max_examples=40, deadline=None)
@given(
    motor=st.sampled_from(list(MotorType)),
    kp=st.floats(0.0, 500.0),
    kd=st.floats(0.0, 5.0),
    start=st.floats(-3.0, 3.0),
    load=st.floats(0.0, 0.05),
)
def test_mit_law_stays_bounded_for_any_gain(motor, kp, kd, start, load):
    model = MotorModel(motor_params(motor, load_inertia=load), angle=start)
    model.command_impedance(0.0, 0.0, kp, kd, 0.0)
    limit = abs(start) + 1.0
    for _ in range(500):
        model.step(DT)
        assert abs(model.angle) < limit
        assert math.isfinite(model.velocity)


def test_when_mit_law_holds_position_expect_converges_to_target():
    model = MotorModel(MOTOR_DEFAULTS[MotorType.DM4310])
    model.command_impedance(1.0, 0.0, 50.0, 1.0, 0.0)
    run(model, 2.0)
    # Coulomb friction 0.05 N·m leaves a dead band of 0.05/50 = 1 mrad around the target.
    assert model.angle == pytest.approx(1.0, abs=1.1e-3)


def test_when_mit_position_offset_expect_target_relative_to_zero():
    model = MotorModel(MOTOR_DEFAULTS[MotorType.DM4310])
    model.command_impedance(0.5, 0.0, 50.0, 1.0, 0.0, position_offset=0.25)
    run(model, 2.0)
    assert model.angle == pytest.approx(0.75, abs=1.1e-3)


def test_load_inertia_is_reflected_through_gear_ratio():
    p = motor_params('m2006', load_inertia=0.36)
    assert p.inertia == pytest.approx(2.5e-6 + 0.36 / 36**2)
    assert p.output_inertia == pytest.approx(2.5e-6 * 36**2 + 0.36)


def test_when_unknown_motor_type_expect_config_error():
    with pytest.raises(SimConfigError, match="unknown motor type 'm3509'"):
        motor_params('m3509')


def test_when_unknown_parameter_expect_config_error():
    with pytest.raises(SimConfigError, match='unknown motor parameter'):
        motor_params('m3508', inertia=1.0)


@pytest.mark.parametrize(
    ('field', 'value', 'message'),
    [
        ('rotor_inertia', -1.0, 'rotor_inertia must be > 0'),
        ('load_inertia', -0.1, 'load_inertia must be >= 0'),
        ('gear_ratio', float('nan'), 'gear_ratio must be finite'),
    ],
)
def test_when_bad_parameter_value_expect_config_error(field, value, message):
    with pytest.raises(SimConfigError, match=message):
        motor_params('m3508', **{field: value})


def test_when_nan_command_expect_value_error():
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508])
    with pytest.raises(ValueError, match='current must be finite'):
        model.command_current(float('nan'))


def test_when_dt_not_positive_expect_value_error():
    model = MotorModel(MOTOR_DEFAULTS[MotorType.M3508])
    with pytest.raises(ValueError, match='dt must be a positive'):
        model.step(0.0)
