import math
from collections import deque

import pytest
from rm_base.control import IncrementalPidConfig, IncrementalPidGains, PidGains
from rm_base.errors import ConfigError, InputRejectedError
from rm_plugins.chassis.modes import (
    ChassisModeController,
    ChassisModeParams,
    ChassisMotionMode,
    FollowParams,
    GyroParams,
    TwistParams,
    TwistWaveform,
    twist_waveform,
)

RAW = ChassisMotionMode.RAW
FOLLOW = ChassisMotionMode.FOLLOW
TWIST = ChassisMotionMode.TWIST
GYRO = ChassisMotionMode.GYRO


def make(
    kp=2.0,
    ki=0.0,
    offset=0.0,
    amplitude=0.6,
    period_s=1.0,
    waveform=TwistWaveform.SINE,
    spin_rate=8.0,
    translating_spin_rate=None,
    translating_speed=1.0,
    latency_s=0.0,
):
    return ChassisModeController(
        ChassisModeParams(
            follow=FollowParams(PidGains(kp=kp, ki=ki, angle_mode=True), offset=offset),
            twist=TwistParams(amplitude=amplitude, period_s=period_s, waveform=waveform),
            gyro=GyroParams(
                spin_rate=spin_rate,
                translating_spin_rate=translating_spin_rate,
                translating_speed=translating_speed,
            ),
            latency_s=latency_s,
        )
    )


def step_pose(x, y, yaw, twist, dt):
    """Move a pose exactly along a chassis-frame twist held for dt (an arc)."""
    vx, vy, wz = twist
    if abs(wz) < 1e-12:
        dx, dy = vx * dt, vy * dt
    else:
        s, c = math.sin(wz * dt), math.cos(wz * dt)
        dx = (s * vx - (1.0 - c) * vy) / wz
        dy = ((1.0 - c) * vx + s * vy) / wz
    cy, sy = math.cos(yaw), math.sin(yaw)
    return x + cy * dx - sy * dy, y + sy * dx + cy * dy, yaw + wz * dt


def test_when_raw_expect_command_passed_through():
    assert make().update(RAW, (1.0, -0.5, 2.0), yaw_joint=1.2, dt=0.01) == (1.0, -0.5, 2.0)


def test_when_follow_and_gimbal_left_of_chassis_expect_chassis_turns_left():
    # phi = 0.5 (gimbal 0.5 rad left of the chassis). The PID sees the chassis heading
    # relative to the gimbal, -0.5, with setpoint 0: wz = kp * (0 - (-0.5)) = 2 * 0.5 = 1.0
    twist = make(kp=2.0).update(FOLLOW, (0.0, 0.0, 0.0), yaw_joint=0.5, dt=0.01)
    assert twist.wz == pytest.approx(1.0)


def test_when_follow_at_offset_expect_no_turn():
    twist = make(offset=0.5).update(FOLLOW, (0.0, 0.0, 0.0), yaw_joint=0.5, dt=0.01)
    assert twist.wz == pytest.approx(0.0)


def test_when_follow_and_gimbal_turning_expect_gimbal_rate_fed_forward():
    # Error 0, so the PID gives 0 and wz is the feed-forward alone: 1.5 rad/s.
    twist = make().update(FOLLOW, (0.0, 0.0, 0.0), 0.0, 0.01, gimbal_yaw_rate=1.5)
    assert twist.wz == pytest.approx(1.5)


def test_when_follow_error_crosses_pi_expect_short_way_round():
    # phi = 3.0, offset -3.0: the short way from 3.0 to -3.0 is +0.2832 rad through pi
    # (2 pi - 6). phi rises when the chassis turns clockwise, so wz < 0:
    # chassis heading -3.0 -> setpoint 3.0: error 6.0 wrapped = 6 - 2 pi = -0.28319;
    # wz = 2 * -0.28319 = -0.56637
    twist = make(kp=2.0, offset=-3.0).update(FOLLOW, (0.0, 0.0, 0.0), 3.0, 0.01)
    assert twist.wz == pytest.approx(2.0 * (6.0 - 2.0 * math.pi))


def test_when_follow_runs_the_incremental_form_expect_the_same_short_way_round():
    gains = IncrementalPidConfig(IncrementalPidGains(kp=2.0, angle_mode=True))
    controller = ChassisModeController(
        ChassisModeParams(
            follow=FollowParams(gains, offset=-3.0),
            twist=TwistParams(amplitude=0.6, period_s=1.0),
            gyro=GyroParams(spin_rate=8.0),
        )
    )
    twist = controller.update(FOLLOW, (0.0, 0.0, 0.0), 3.0, 0.01)
    assert twist.wz == pytest.approx(2.0 * (6.0 - 2.0 * math.pi))


def test_when_follow_with_gimbal_turned_left_expect_forward_command_drives_left():
    # Gimbal pointing along chassis +y (phi = pi/2): "forward" in the gimbal frame is
    # chassis +y. With dphi/dt = 0 nothing is added to the rotation angle.
    twist = make(kp=0.0).update(FOLLOW, (1.0, 0.0, 0.0), math.pi / 2, 0.01, yaw_joint_rate=0.0)
    assert (twist.vx, twist.vy) == pytest.approx((0.0, 1.0), abs=1e-12)


def test_when_follow_closed_loop_with_turning_gimbal_expect_no_steady_lag():
    controller = make(kp=5.0, offset=0.2)
    dt, gimbal_rate = 0.005, 1.0
    gimbal_yaw = chassis_yaw = 0.0
    for _ in range(600):  # 3 s, 15 time constants of 1 / kp = 0.2 s
        phi = gimbal_yaw - chassis_yaw
        wz = controller.update(FOLLOW, (0.0, 0.0, 0.0), phi, dt, gimbal_yaw_rate=gimbal_rate).wz
        chassis_yaw += wz * dt
        gimbal_yaw += gimbal_rate * dt
    # With the gimbal rate fed forward the error obeys e' = -kp e (discretely
    # e_{k+1} = (1 - kp dt) e_k): 0.2 * 0.975^600 = 5e-8. Without it, P alone would lag
    # by gimbal_rate / kp = 0.2 rad.
    assert gimbal_yaw - chassis_yaw == pytest.approx(0.2, abs=1e-6)


def test_when_mode_changes_expect_pid_integral_restarted():
    controller = make(kp=0.0, ki=1.0)
    # phi = 1: heading error 1; I = 1 * 1 * 0.1 = 0.1 per update.
    assert controller.update(FOLLOW, (0, 0, 0), 1.0, 0.1).wz == pytest.approx(0.1)
    assert controller.update(FOLLOW, (0, 0, 0), 1.0, 0.1).wz == pytest.approx(0.2)
    controller.update(RAW, (0, 0, 0), 1.0, 0.1)
    # Back in FOLLOW: a fresh integral, 0.1 again (not 0.3).
    assert controller.update(FOLLOW, (0, 0, 0), 1.0, 0.1).wz == pytest.approx(0.1)


@pytest.mark.parametrize(
    ('waveform', 'fraction', 'value', 'rate'),
    [
        # sine, T = 2 s: f = sin(pi t), f' = pi cos(pi t)
        (TwistWaveform.SINE, 0.0, 0.0, math.pi),
        (TwistWaveform.SINE, 0.25, 1.0, 0.0),
        (TwistWaveform.SINE, 0.75, -1.0, 0.0),
        # triangle, T = 2 s: slope 4 / T = 2 per s; up to 1 at T/4, down to -1 at 3T/4
        (TwistWaveform.TRIANGLE, 0.125, 0.5, 2.0),
        (TwistWaveform.TRIANGLE, 0.375, 0.5, -2.0),
        (TwistWaveform.TRIANGLE, 0.5, 0.0, -2.0),
        (TwistWaveform.TRIANGLE, 0.625, -0.5, -2.0),
        (TwistWaveform.TRIANGLE, 0.875, -0.5, 2.0),
        (TwistWaveform.TRIANGLE, 1.125, 0.5, 2.0),  # periodic
    ],
)
def test_twist_waveform_values(waveform, fraction, value, rate):
    f, df = twist_waveform(waveform, fraction * 2.0, 2.0)
    assert f == pytest.approx(value, abs=1e-12)
    assert df == pytest.approx(rate, abs=1e-12)


def test_when_twist_expect_target_swings_chassis_left_first():
    controller = make(amplitude=0.6, period_s=1.0, waveform=TwistWaveform.TRIANGLE)
    controller.update(TWIST, (0, 0, 0), 0.0, 0.01)
    assert controller.target_yaw_joint == pytest.approx(0.0)  # entering: phase 0
    for _ in range(25):
        controller.update(TWIST, (0, 0, 0), 0.0, 0.01)
    # t = 0.25 s = T/4: triangle at its peak 1; chassis heading relative to the gimbal
    # +0.6 (turned left), so phi target = -0.6.
    assert controller.target_yaw_joint == pytest.approx(-0.6)


def test_when_twist_closed_loop_expect_chassis_tracks_swing():
    controller = make(kp=10.0, amplitude=0.6, period_s=1.0)
    dt = 0.002
    chassis_yaw = 0.0  # gimbal held at world yaw 0
    errors = []
    for step in range(1500):  # 3 periods
        wz = controller.update(TWIST, (0.0, 0.0, 0.0), -chassis_yaw, dt).wz
        chassis_yaw += wz * dt
        if step >= 500:
            # After this update the chassis is where the target is at t = (step + 1) dt:
            # heading 0.6 sin(2 pi t).
            errors.append(chassis_yaw - 0.6 * math.sin(2 * math.pi * (step + 1) * dt))
    # The swing rate is fed forward, so only the discretisation is left: the feed-forward
    # holds the rate of the start of each step, off by about A (2 pi / T)² dt² / 2 =
    # 0.6 * 39.5 * 4e-6 / 2 = 4.7e-5 per step, which the P term (kp dt = 0.02) settles at
    # about 4.7e-5 / 0.02 = 2.4e-3 rad.
    assert max(abs(e) for e in errors) < 5e-3


def test_when_reentering_twist_expect_swing_restarts():
    controller = make()
    for _ in range(10):
        controller.update(TWIST, (0, 0, 0), 0.0, 0.01)
    assert controller.target_yaw_joint != pytest.approx(0.0)
    controller.update(FOLLOW, (0, 0, 0), 0.0, 0.01)
    controller.update(TWIST, (0, 0, 0), 0.0, 0.01)
    assert controller.target_yaw_joint == pytest.approx(0.0)


def test_when_gyro_expect_constant_spin():
    assert make(spin_rate=8.0).update(GYRO, (0.0, 0.0, 3.0), 1.0, 0.01).wz == 8.0


@pytest.mark.parametrize(
    ('spin', 'command', 'expected'),
    [
        # |v| = hypot(0.6, 0.8) = 1.0 m/s of 2.0: halfway from 10 to 4 rad/s = 7
        (10.0, (0.6, 0.8, 0.0), 7.0),
        (-10.0, (0.6, 0.8, 0.0), -7.0),
        # at or above 2 m/s: 4 rad/s
        (10.0, (3.0, 0.0, 0.0), 4.0),
        (10.0, (0.0, 0.0, 0.0), 10.0),
    ],
)
def test_when_gyro_translating_expect_spin_reduced(spin, command, expected):
    controller = make(spin_rate=spin, translating_spin_rate=4.0, translating_speed=2.0)
    assert controller.update(GYRO, command, 0.0, 0.01).wz == pytest.approx(expected)


def drive_gyro(controller_latency_s, plant_latency_steps, seconds=3.0):
    """Spin in GYRO with a gimbal-frame command (1.5, 0) and the gimbal held at world yaw
    0.3; return the world displacement after a 0.5 s warm-up and the largest distance of
    the sampled path from the straight line through its start along the gimbal heading."""
    dt, gimbal_yaw = 0.01, 0.3
    controller = make(spin_rate=8.0, latency_s=controller_latency_s)
    pending = deque([(0.0, 0.0, 0.0)] * plant_latency_steps)
    x = y = yaw = 0.0
    plant = (0.0, 0.0, 0.0)
    start = None
    off_line = 0.0
    warm_up = round(0.5 / dt)
    for step in range(warm_up + round(seconds / dt)):
        if step == warm_up:
            start = (x, y)
        if start is not None:
            # Distance from the line through start along the gimbal heading.
            off_line = max(
                off_line,
                abs(-math.sin(gimbal_yaw) * (x - start[0]) + math.cos(gimbal_yaw) * (y - start[1])),
            )
        # The yaw motor measures dphi/dt = gimbal rate (0) - the chassis spin now.
        twist = controller.update(
            GYRO, (1.5, 0.0, 0.0), gimbal_yaw - yaw, dt, yaw_joint_rate=-plant[2]
        )
        pending.append(tuple(twist))
        plant = pending.popleft()
        x, y, yaw = step_pose(x, y, yaw, plant, dt)
    return (x - start[0], y - start[1]), off_line


def test_when_gyro_with_latency_compensated_expect_straight_world_path():
    # 8 rad/s with 20 ms latency (2 steps) at 100 Hz. Rotating by phi + dphi/dt (0.02 + 0.005)
    # is the mean heading over the step the command acts in, so each step's chord points
    # exactly along the gimbal heading and the sampled path is a straight line.
    (dx, dy), off_line = drive_gyro(controller_latency_s=0.02, plant_latency_steps=2)
    assert math.atan2(dy, dx) == pytest.approx(0.3, abs=1e-3)
    assert off_line < 1e-3  # m, over 3 s and about 4.5 m
    # A chord of an arc is shorter than the arc: 1.5 m/s * 3 s * sinc(8 * 0.01 / 2) =
    # 4.5 * 0.99973 = 4.4988 m.
    assert math.hypot(dx, dy) == pytest.approx(4.4988, abs=1e-3)


def test_when_gyro_latency_not_compensated_expect_path_turned_by_spin_times_latency():
    # The controller assumes no latency but the wheels act 20 ms late: the chassis has
    # turned 8 * 0.02 = 0.16 rad further (counter-clockwise) than the command assumed, so
    # the path heads 0.3 + 0.16 = 0.46 rad. This is what the compensation removes.
    (dx, dy), _ = drive_gyro(controller_latency_s=0.0, plant_latency_steps=2)
    assert math.atan2(dy, dx) == pytest.approx(0.46, abs=1e-3)


@pytest.mark.parametrize(
    ('kwargs', 'message'),
    [
        ({'mode': 'follow'}, 'unknown chassis motion mode'),
        ({'dt': 0.0}, 'dt'),
        ({'dt': math.nan}, 'dt'),
        ({'command': (math.nan, 0.0, 0.0)}, 'finite'),
        ({'command': (1.0, 0.0)}, r'\(vx, vy, wz\)'),
        ({'yaw_joint': math.inf}, 'finite'),
        ({'gimbal_yaw_rate': math.nan}, 'finite'),
        ({'yaw_joint_rate': math.nan}, 'finite'),
    ],
)
def test_when_update_input_invalid_expect_rejected(kwargs, message):
    args = {'mode': FOLLOW, 'command': (0.0, 0.0, 0.0), 'yaw_joint': 0.0, 'dt': 0.01}
    args.update(kwargs)
    mode, command = args.pop('mode'), args.pop('command')
    yaw_joint, dt = args.pop('yaw_joint'), args.pop('dt')
    with pytest.raises(InputRejectedError, match=message):
        make().update(mode, command, yaw_joint, dt, **args)


def test_when_follow_gains_not_angle_mode_expect_config_error():
    with pytest.raises(ConfigError, match='angle_mode'):
        FollowParams(PidGains(kp=1.0))
    with pytest.raises(ConfigError, match='angle_mode'):
        FollowParams(IncrementalPidConfig(IncrementalPidGains(kp=1.0)))


@pytest.mark.parametrize(
    ('build', 'message'),
    [
        (lambda: TwistParams(amplitude=math.pi, period_s=1.0), 'amplitude'),
        (lambda: TwistParams(amplitude=-0.1, period_s=1.0), 'amplitude'),
        (lambda: TwistParams(amplitude=0.5, period_s=0.0), 'period_s'),
        (lambda: TwistParams(amplitude=0.5, period_s=1.0, waveform='sine'), 'waveform'),
        (lambda: GyroParams(spin_rate=math.nan), 'spin_rate'),
        (lambda: GyroParams(spin_rate=5.0, translating_spin_rate=-1.0), 'translating_spin'),
        (lambda: GyroParams(spin_rate=5.0, translating_speed=0.0), 'translating_speed'),
        (lambda: FollowParams(PidGains(angle_mode=True), offset=math.inf), 'offset'),
    ],
)
def test_when_mode_params_invalid_expect_config_error(build, message):
    with pytest.raises(ConfigError, match=message):
        build()


def test_when_latency_negative_expect_config_error():
    with pytest.raises(ConfigError, match='latency_s'):
        ChassisModeParams(
            follow=FollowParams(PidGains(angle_mode=True)),
            twist=TwistParams(amplitude=0.5, period_s=1.0),
            gyro=GyroParams(spin_rate=5.0),
            latency_s=-0.01,
        )
