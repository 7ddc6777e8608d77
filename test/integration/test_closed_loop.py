"""Closed loops of the CAN layer on rm_sim, deterministic: hardware and world in lockstep;
README's "Motors" example among them.

Each step advances a fake clock by 1 ms, runs one ``CanHardware.tick`` (update, pack,
send: the simulated motors take the frames), one ``SimWorld.step`` (physics, then the
motors' feedback), and waits until the bus receive thread has handed every joint its
feedback of this step. No wall clock enters the loop, so every run gives the same
numbers; the waits only absorb thread hand-over.

The gains are the ones a robot config would set (the hardware layer has no default
gains); the numbers in the docstrings were measured with them and are asserted with margin.
"""

import itertools
import math
import os
import time

from rm_base.hardware import MODE_MIT, MODE_POSITION, MODE_VELOCITY, CanHardware
from rm_base.motors.lk.actuator import Mf9025
from rm_base.sim import DJI_ENCODER_COUNTS, SimWorld
from support.user_session import readme_yaml

from rm_base import motors as motor_families

MS = 1_000_000  # [ns]
_channels = itertools.count()


class Lockstep:
    """CanHardware on one rm_sim channel of a stepped world, advanced 1 ms at a time."""

    def __init__(self, joints, motors):
        self.channel = f'rm-closed-loop-{os.getpid()}-{next(_channels)}'
        self.world = SimWorld(timing='stepped')
        self.world.add_channel(self.channel, motors)
        self.now_ns = 1_000 * MS
        config = {
            'buses': {
                'can0': {
                    'interface': 'rm_sim',
                    'channel': self.channel,
                    'options': {'world': self.world},
                    'receive_timeout_s': 0.01,
                }
            },
            'joints': joints,
        }
        self.hw = CanHardware(
            config, clock_ns=lambda: self.now_ns, receive_in_loop=False, families=motor_families,
        )

    def __enter__(self):
        self.hw.open()
        self.world.step(1)  # first DJI feedback
        return self

    def __exit__(self, *exc):
        self.hw.shutdown()
        self.world.close()

    def command(self, name, mode, **values):
        self.hw.set_command(name, mode, now_ns=self.now_ns, **values)

    def step(self):
        """One control period: tick, physics, then wait for this step's feedback."""
        self.now_ns += MS
        self.hw.tick(self.now_ns)
        self.world.step(1)
        deadline = time.monotonic() + 10.0  # generous: only thread hand-over is waited for
        actuators = self.hw.actuators.values()
        while not all(
            a.feedback is not None and a.feedback.stamp_ns >= self.now_ns for a in actuators
        ):
            if time.monotonic() > deadline:
                raise AssertionError(f'no feedback at step {self.now_ns}: {self.hw.states()}')
            time.sleep(20e-6)

    def state(self, name):
        return next(s for s in self.hw.states() if s.name == name)


def test_m3508_velocity_step_settles_fast_without_overshoot():
    """M3508 (no load), velocity step 0 -> 30 rad/s at the output shaft, as reported by the
    bridge (the feedback the ESC sends).

    Gains: velocity_pid kp 0.5 N·m/(rad/s), ki 5 N·m/rad, integral_separation 3 rad/s
    (no wind-up while the output saturates), output_limit 6 N·m (= max_effort).
    Measured: 95 % (28.5 rad/s) after 34 ms, within ±2 % from 43 ms on, overshoot 0.0 %
    (peak 30.00 rad/s), steady-state error < 0.01 rad/s. Asserted: 95 % before 60 ms,
    within ±2 % from 80 ms, overshoot < 3 %.
    Lower bound for comparison: at the 6 N·m limit the output inertia
    1.2e-5 kg·m² x (3591/187)² = 4.4e-3 kg·m² accelerates at ~1360 rad/s², i.e. 22 ms to
    30 rad/s before friction and back-EMF.
    """
    target = 30.0
    joints = {
        'wheel': {
            'type': 'm3508',
            'bus': 'can0',
            'id': 1,
            'velocity_pid': {'kp': 0.5, 'ki': 5.0, 'integral_separation': 3.0, 'output_limit': 6.0},
        }
    }
    with Lockstep(joints, [{'type': 'm3508', 'id': 1, 'name': 'wheel'}]) as rig:
        velocity = []
        for _ in range(400):
            rig.command('wheel', MODE_VELOCITY, velocity=target)
            rig.step()
            velocity.append(rig.state('wheel').velocity)
    t95_ms = next(i for i, v in enumerate(velocity) if v >= 0.95 * target) + 1
    outside_2pct = [i + 1 for i, v in enumerate(velocity) if abs(v - target) > 0.02 * target]
    overshoot = (max(velocity) - target) / target
    assert t95_ms < 60
    assert outside_2pct[-1] < 80
    assert overshoot < 0.03
    assert abs(velocity[-1] - target) < 0.01 * target


def test_gm6020_position_hold_returns_after_a_torque_disturbance():
    """GM6020 (voltage mode) holding 0 rad with a 0.01 kg·m² gimbal load; an external
    0.6 N·m torque on the output for 50 ms, then released.

    Gains: position_pid kp 30 1/s, output_limit 10 rad/s; velocity_pid kp 0.5
    N·m/(rad/s), ki 3 N·m/rad, integral_separation 1 rad/s, output_limit 1.2 N·m.
    Measured: peak deviation 0.029 rad (1.7°), back within 0.005 rad 59 ms after the
    release and staying there, final error 0 encoder ticks. Asserted: a visible push
    (> 0.01 rad) that stays below 0.05 rad, within 0.005 rad before 120 ms after the
    release, final error within 2 encoder ticks (2 x 2π/8192 = 1.5 mrad).
    """
    joints = {
        'yaw': {
            'type': 'gm6020',
            'bus': 'can0',
            'id': 1,
            'position_pid': {'kp': 30.0, 'output_limit': 10.0},
            'velocity_pid': {'kp': 0.5, 'ki': 3.0, 'integral_separation': 1.0, 'output_limit': 1.2},
        }
    }
    motors = [{'type': 'gm6020', 'id': 1, 'name': 'yaw', 'load_inertia': 0.01}]
    push_ms, release_ms = 200, 250
    with Lockstep(joints, motors) as rig:
        model = rig.world.motor('yaw').model
        position = []
        for k in range(700):
            if k == push_ms:
                model.external_torque = 0.6  # [N·m]
            elif k == release_ms:
                model.external_torque = 0.0
            rig.command('yaw', MODE_POSITION, position=0.0)
            rig.step()
            position.append(rig.state('yaw').position)
    peak = max(abs(p) for p in position[push_ms:])
    outside = [k for k, p in enumerate(position) if abs(p) > 0.005]
    assert max(abs(p) for p in position[100:push_ms]) < 1e-3  # held before the push
    assert 0.01 < peak < 0.05
    assert outside[-1] - release_ms < 120
    assert abs(position[-1]) <= 2 * 2 * math.pi / DJI_ENCODER_COUNTS


def test_dm4310_mit_mode_tracks_a_slow_sine():
    """DM4310 in native MIT mode (the motor closes kp/kd itself), tracking
    q = 0.5 sin(2π·0.5 t) rad with the velocity feed-forward, kp 20 N·m/rad, kd 1 N·m·s/rad.

    Measured after the first 0.5 s: max |error| 5.4 mrad, RMS 3.6 mrad (the feedback is
    one reply, i.e. one tick, behind the command). Asserted: max < 12 mrad, RMS < 8 mrad.
    """
    amplitude, frequency = 0.5, 0.5  # [rad], [Hz]
    omega = 2 * math.pi * frequency
    joints = {'pitch': {'type': 'dm4310', 'bus': 'can0', 'id': 2}}
    with Lockstep(joints, [{'type': 'dm4310', 'id': 2, 'name': 'pitch'}]) as rig:
        errors = []
        for k in range(3000):
            t = (k + 1) * 1e-3
            target = amplitude * math.sin(omega * t)
            rig.command(
                'pitch',
                MODE_MIT,
                position=target,
                velocity=amplitude * omega * math.cos(omega * t),
                kp=20.0,
                kd=1.0,
            )
            rig.step()
            errors.append(rig.state('pitch').position - target)
        assert rig.state('pitch').online and rig.state('pitch').error_code == 0
    tail = errors[500:]
    rms = math.sqrt(sum(e * e for e in tail) / len(tail))
    assert max(abs(e) for e in tail) < 0.012
    assert rms < 0.008


def test_lockstep_runs_are_identical():
    """The same 100 ms of an M3508 step, run twice, gives bit-identical states."""

    def run():
        joints = {'wheel': {'type': 'm3508', 'bus': 'can0', 'id': 1, 'velocity_pid': {'kp': 0.5}}}
        with Lockstep(joints, [{'type': 'm3508', 'id': 1, 'name': 'wheel'}]) as rig:
            trace = []
            for _ in range(100):
                rig.command('wheel', MODE_VELOCITY, velocity=10.0)
                rig.step()
                trace.append(rig.state('wheel'))
        return trace

    first, second = run(), run()
    assert first[-1].velocity > 5.0
    assert first == second


class LkLockstep(Lockstep):
    """The same, waiting for each LK motor's reply of this step, whatever its kind (a
    status read's reply carries no position)."""

    ticks = 0

    def step(self):
        self.now_ns += MS
        self.hw.tick(self.now_ns)
        self.world.step(1)
        self.ticks += 1
        deadline = time.monotonic() + 10.0
        while not all(a.replies >= self.ticks for a in self.hw.actuators.values()):
            if time.monotonic() > deadline:
                raise AssertionError(f'no reply at step {self.now_ns}: {self.hw.states()}')
            time.sleep(20e-6)


def test_an_lk_mf9025_holds_its_position_against_a_push_on_its_torque_command():
    """MF9025 (direct drive, 0xA1 torque commands, a status read every 100 ms) holding
    0.5 rad with a 0.02 kg·m² load; an external 1 N·m torque for 100 ms, then released.

    Gains: position_pid kp 20 1/s, output_limit 10 rad/s; velocity_pid kp 1.0
    N·m/(rad/s), ki 10 N·m/rad, integral_separation 1 rad/s, output_limit 5 N·m.
    Measured: 0.5 rad within 2e-5 rad before the push, peak deviation 0.031 rad, back
    within 0.005 rad 218 ms after the release. Asserted: within 0.01 rad before the push, a
    visible push below 0.06 rad, back within 0.005 rad before 400 ms after the release and
    at the end, every status read answered (one frame in 100) and no hold.
    """
    joints = {
        'leg': {
            'type': 'mf9025', 'bus': 'can0', 'id': 1,
            'position_pid': {'kp': 20.0, 'output_limit': 10.0},
            'velocity_pid': {'kp': 1.0, 'ki': 10.0, 'integral_separation': 1.0,
                             'output_limit': 5.0},
        }
    }
    motors = [{'type': 'mf9025', 'id': 1, 'name': 'leg', 'load_inertia': 0.02}]
    push_ms, release_ms, end_ms = 600, 700, 1500
    with LkLockstep(joints, motors) as rig:
        model = rig.world.motor('leg').model
        position = []
        for k in range(end_ms):
            if k == push_ms:
                model.external_torque = 1.0  # [N·m]
            elif k == release_ms:
                model.external_torque = 0.0
            rig.command('leg', MODE_POSITION, position=0.5)
            rig.step()
            position.append(rig.state('leg').position)
        leg = rig.hw.actuators['leg']
        assert leg.status_frames == end_ms // 100
        assert leg.hold_reason.value == 'none' and leg.motor_on is True
        assert rig.world.motor('leg').stats.ignored_frames == 0
    assert abs(position[push_ms - 1] - 0.5) < 0.01
    peak = max(abs(p - 0.5) for p in position[push_ms:])
    outside = [k for k, p in enumerate(position) if abs(p - 0.5) > 0.005]
    assert 0.01 < peak < 0.06
    assert outside[-1] - release_ms < 400
    assert abs(position[-1] - 0.5) < 0.005


def test_an_lk_mg4010_behind_its_gear_reaches_and_holds_a_position():
    """MG4010E-i10: the rotor encoder unwrapped through 10:1 to an output 2 rad away
    (more than three rotor turns), held there, within its 4.5 N·m. Measured: within 0.005 rad
    from 896 ms on, 4e-6 rad off at 2 s, the joint's reading 3e-6 rad from the simulated
    shaft's. Asserted: within 0.005 rad for the last 500 ms; the reading within two encoder
    ticks of the truth."""
    joints = {
        'arm': {
            'type': 'mg4010', 'bus': 'can0', 'id': 2,
            'position_pid': {'kp': 10.0, 'output_limit': 5.0},
            'velocity_pid': {'kp': 0.5, 'ki': 5.0, 'integral_separation': 1.0,
                             'output_limit': 4.5},
        }
    }
    motors = [{'type': 'mg4010', 'id': 2, 'name': 'arm', 'load_inertia': 0.01}]
    with LkLockstep(joints, motors) as rig:
        position = []
        for _ in range(2000):
            rig.command('arm', MODE_POSITION, position=2.0)
            rig.step()
            position.append(rig.state('arm').position)
        held = position[-1]
        truth = rig.world.motor('arm').model.angle
    assert max(abs(p - 2.0) for p in position[1500:]) < 0.005
    assert abs(truth - held) < 2 * math.pi / 65536 * 2  # the joint reads the true angle


def readme_joints() -> dict:
    """The joints of README's "Motors" example, as written there."""
    return readme_yaml('Motors')['can_bridge']['ros__parameters']['joints']


def test_the_readme_lk_joint_holds_a_position_on_its_simulated_motor():
    joints = readme_joints()
    (name,) = joints
    motors = [{'type': 'mf9025', 'id': joints[name]['id'], 'name': name, 'load_inertia': 0.02}]
    assert motor_families.family_of(joints[name]['type']).name == 'lk'
    with LkLockstep(joints, motors) as rig:
        assert isinstance(rig.hw.actuators[name], Mf9025)
        for _ in range(1000):
            rig.command(name, MODE_POSITION, position=0.3)
            rig.step()
        assert abs(rig.state(name).position - 0.3) < 0.005
        assert rig.hw.actuators[name].status_frames == 10
