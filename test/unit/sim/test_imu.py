"""Simulated HiPNUC IMU: real 0x91 frames on a pseudo-terminal, read through pyserial."""

import math
import os
import threading
import time

import numpy as np
import pytest
import serial
from rm_base.geometry import quaternion_from_rpy
from rm_base.hardware.protocols import hipnuc
from rm_base.sim import SimBus, SimConfigError, SimWorld

from .helpers import unique_channel

FREE = {'coulomb_friction': 0.0, 'viscous_friction': 0.0}
WHEELS = ['wheel_fl', 'wheel_fr', 'wheel_rl', 'wheel_rr']
G = hipnuc.STANDARD_GRAVITY


def robot(imu, *, yaw=0.0, gimbal_yaw=0.0, pitch=0.0):
    motors = [{'type': 'm3508', 'id': i + 1, 'name': n, **FREE} for i, n in enumerate(WHEELS)]
    motors += [
        {'type': 'gm6020', 'id': 1, 'name': 'yaw', 'initial_position': gimbal_yaw, **FREE},
        {'type': 'gm6020', 'id': 2, 'name': 'pitch', 'initial_position': pitch, **FREE},
    ]
    body = {
        'initial_pose': [0.0, 0.0, yaw],
        'chassis': {
            'type': 'mecanum',
            'motors': WHEELS,
            'wheelbase': 0.4,
            'track': 0.3,
            'wheel_radius': 0.076,
        },
        'gimbal': {'yaw': {'motor': 'yaw'}, 'pitch': {'motor': 'pitch'}},
    }
    return {
        'timing': 'stepped',
        'channels': {unique_channel(): motors},
        'body': body,
        'imus': [imu],
    }


def read_samples(port, count, timeout=10.0):
    """Read until the parser has count samples (the frames are already in the pty)."""
    parser = hipnuc.HipnucParser()
    samples = []
    deadline = time.monotonic() + timeout
    while len(samples) < count and time.monotonic() < deadline:
        samples += parser.feed(port.read(port.in_waiting or 1))
    assert parser.crc_errors == 0
    return samples


def assert_quat_close(got_wxyz, expected_xyzw, tol=1e-6):
    x, y, z, w = expected_xyzw
    got = np.array(got_wxyz)
    want = np.array([w, x, y, z])
    # q and -q are the same rotation.
    assert min(np.abs(got - want).max(), np.abs(got + want).max()) < tol


@pytest.fixture
def imu_path(tmp_path, monkeypatch):
    monkeypatch.setenv('RM_SIM_TEST_DIR', str(tmp_path))
    return '${RM_SIM_TEST_DIR}/dev/imu'


def test_imu_frames_read_through_pyserial_match_the_gimbal_orientation(imu_path, tmp_path):
    # Chassis heading 0.5 rad, gimbal yaw joint 0.3, pitch joint -0.2 (nose up):
    # the gimbal IMU's orientation is Rz(0.8) Ry(-0.2); at rest it measures gravity only.
    config = robot(
        {'path': imu_path, 'mount': 'gimbal', 'rate_hz': 100}, yaw=0.5, gimbal_yaw=0.3, pitch=-0.2
    )
    with SimWorld.from_config(config) as world:
        link = tmp_path / 'dev' / 'imu'
        assert link.is_symlink()
        with serial.Serial(str(link), 115200, timeout=1.0) as port:
            world.step(50)  # 100 Hz: 5 frames in 50 ms
            samples = read_samples(port, 5)
    assert len(samples) == 5
    sample = samples[-1]
    assert_quat_close(sample.quat, quaternion_from_rpy(0.0, -0.2, 0.8))
    assert sample.euler == pytest.approx((0.0, -0.2, 0.8), abs=1e-6)
    # Specific force seen from a frame pitched by p: Ry(p)^T (0, 0, g) = g (-sin p, 0, cos p);
    # nose up (p < 0), the sensor's x axis points partly up and reads +g sin 0.2.
    assert sample.acc == pytest.approx((G * math.sin(0.2), 0.0, G * math.cos(0.2)), abs=1e-5)
    assert sample.gyr == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert sample.system_time_ms == 50
    assert [s.system_time_ms for s in samples] == [10, 20, 30, 40, 50]


def test_chassis_imu_measures_the_chassis_spin(imu_path):
    config = robot({'path': imu_path, 'mount': 'chassis', 'rate_hz': 200, 'baudrate': 921600})
    with SimWorld.from_config(config) as world:
        imu = world.imu()
        # In-place rotation at 1 rad/s: FL, RL back, FR, RR forward at (lx+ly)/r rad/s.
        speed = (0.2 + 0.15) / 0.076
        for name, sign in zip(WHEELS, (-1, 1, -1, 1), strict=True):
            world.motor(name).model.reset(velocity=sign * speed)
        with serial.Serial(imu.path, 921600, timeout=1.0) as port:
            world.step(100)
            samples = read_samples(port, 20)
    last = samples[-1]
    assert last.gyr == pytest.approx((0.0, 0.0, 1.0), abs=1e-6)
    assert last.euler[2] == pytest.approx(0.1, abs=1e-5)  # 100 ms at 1 rad/s


def test_imu_mount_rotation_is_applied(imu_path):
    # Mounted upside down (roll pi): gravity reads -g on the sensor's z.
    config = robot({'path': imu_path, 'mount': 'chassis', 'mount_rpy': [math.pi, 0.0, 0.0]})
    with SimWorld.from_config(config) as world:
        sample = world.imu().sample()
    assert sample['acc'] == pytest.approx((0.0, 0.0, -G), abs=1e-9)


def test_imu_writes_frames_at_its_rate(imu_path):
    with SimWorld.from_config(robot({'path': imu_path, 'rate_hz': 50})) as world:
        world.step(1000)
        assert world.imu().frames_written == 50


def test_when_nobody_reads_expect_writes_never_block(imu_path):
    # 1 kHz of 82-byte frames for 2 s is 164 kB, far beyond a terminal's buffer.
    config = robot({'path': imu_path, 'rate_hz': 1000, 'baudrate': 2_000_000})
    with SimWorld.from_config(config) as world:
        world.step(2000)
        imu = world.imu()
        assert imu.frames_written + imu.frames_dropped == 2000
        assert imu.frames_written > 0


@pytest.mark.parametrize('mount', ['gimbal', 'chassis'])
@pytest.mark.parametrize(
    ('pose', 'mount_rpy'),
    [
        ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
        ((2.5, -0.7, 0.3), (0.0, 0.0, 0.0)),
        ((-3.0, 2.9, -0.4), (0.1, -0.2, 3.0)),
        ((1.0, 0.5, 1.4), (math.pi, 0.0, -math.pi / 2)),
    ],
)
def test_sample_matches_the_rotation_matrix_reference(imu_path, mount, pose, mount_rpy):
    # sample() works in plain floats; sensor_rotation() and rm_base.geometry are the
    # reference (numpy, validated)
    from rm_base.geometry import quaternion_from_rotation_matrix, rpy_from_quaternion

    yaw, gimbal_yaw, pitch = pose
    imu_config = {
        'path': imu_path,
        'mount': mount,
        'mount_rpy': list(mount_rpy),
        'magnetic_field': [20.0, -5.0, 40.0],
    }
    config = robot(imu_config, yaw=yaw, gimbal_yaw=gimbal_yaw, pitch=pitch)
    with SimWorld.from_config(config) as world:
        body, imu = world.body, world.imu()
        body.twist = (0.3, -0.2, 1.7)
        body.linear_acceleration = (0.8, -1.1)
        rotation = imu.sensor_rotation()
        q = quaternion_from_rotation_matrix(rotation)
        expected = {
            'acc': rotation.T @ (body.world_acceleration() + np.array([0.0, 0.0, G])),
            'gyr': rotation.T @ body.angular_velocity(imu.mount),
            'mag': rotation.T @ imu.magnetic_field,
            'quat': (q.w, q.x, q.y, q.z),
            'euler': rpy_from_quaternion(q),
        }
        got = imu.sample()
    for key, value in expected.items():
        np.testing.assert_allclose(got[key], value, atol=1e-9, err_msg=key)


def test_when_a_terminal_write_is_slow_expect_the_world_lock_free(imu_path):
    # Every bus send waits for the world lock; a terminal write (a system call that took
    # milliseconds on a loaded machine, bench/) must not hold it.
    config = robot({'path': imu_path, 'rate_hz': 1000, 'baudrate': 2_000_000})
    with SimWorld.from_config(config) as world:
        imu = world.imu()
        writing, release = threading.Event(), threading.Event()
        write = imu.write

        def slow_write(data):
            writing.set()
            release.wait(5.0)
            write(data)

        imu.write = slow_write
        # at 1 kHz the first frame is due at the end of the first tick
        stepper = threading.Thread(target=world.step, args=(1,))
        stepper.start()
        try:
            assert writing.wait(5.0)
            free = world.lock.acquire(timeout=2.0)
            if free:
                world.lock.release()
        finally:
            release.set()
            stepper.join(5.0)
        assert free
        assert imu.frames_written == 1


def test_when_closed_expect_late_frames_dropped(imu_path):
    with SimWorld.from_config(robot({'path': imu_path})) as world:
        imu = world.imu()
        frame = imu.frame(0)
    imu.write(frame)
    assert (imu.frames_written, imu.frames_dropped) == (0, 1)


def test_frame_is_a_valid_hipnuc_frame(imu_path):
    with SimWorld.from_config(robot({'path': imu_path})) as world:
        frame = world.imu().frame(1234 * 1_000_000)
    assert len(frame) == 82
    sample = hipnuc.decode_payload(hipnuc.decode_frame(frame))
    assert sample.system_time_ms == 1234
    assert sample.temperature == 25


def test_frame_carries_the_device_clock_when_given(imu_path):
    with SimWorld.from_config(robot({'path': imu_path})) as world:
        frame = world.imu().frame(1234 * 1_000_000, device_ns=98_765 * 1_000_000)
    assert hipnuc.decode_payload(hipnuc.decode_frame(frame)).system_time_ms == 98_765


@pytest.mark.realtime
def test_when_running_in_real_time_expect_the_counter_on_real_time(imu_path):
    # A real IMU's counter runs on whatever the simulation's clock does (it slips when the
    # machine is starved): the world hands it the real-time clock.
    config = robot({'path': imu_path, 'rate_hz': 100})
    config['timing'] = 'realtime'
    with SimWorld.from_config(config) as world, \
            serial.Serial(str(world.imu().path), 115200, timeout=1.0) as port:
        world.start()
        samples = read_samples(port, 3)
        read_ms = time.perf_counter_ns() // 1_000_000
        sim_ms = world.time_ns // 1_000_000
    counters = [s.system_time_ms for s in samples]
    assert all((read_ms - c) % 2**32 <= 5_000 for c in counters), (counters, read_ms)  # uint32
    assert abs(read_ms - sim_ms) > 10_000  # perf_counter is not the sim's clock here


def test_when_closed_expect_symlink_removed(imu_path, tmp_path):
    world = SimWorld.from_config(robot({'path': imu_path}))
    link = tmp_path / 'dev' / 'imu'
    assert link.is_symlink()
    world.close()
    assert not os.path.lexists(link)
    assert world.imu().closed


def test_when_stale_symlink_exists_expect_replaced(imu_path, tmp_path):
    (tmp_path / 'dev').mkdir()
    (tmp_path / 'dev' / 'imu').symlink_to('/dev/null')
    with SimWorld.from_config(robot({'path': imu_path})) as world:
        assert os.readlink(tmp_path / 'dev' / 'imu') == world.imu().device_path


def test_when_path_is_a_regular_file_expect_config_error(imu_path, tmp_path):
    (tmp_path / 'dev').mkdir()
    (tmp_path / 'dev' / 'imu').write_text('')
    with pytest.raises(SimConfigError, match='exists and is not a symlink'):
        SimWorld.from_config(robot({'path': imu_path}))


def test_when_path_uses_unset_variable_expect_config_error(monkeypatch):
    monkeypatch.delenv('RM_SIM_UNSET_VAR', raising=False)
    with pytest.raises(SimConfigError, match='unset environment variable'):
        SimWorld.from_config(robot({'path': '/tmp/${RM_SIM_UNSET_VAR}/imu'}))


def test_when_rate_exceeds_baudrate_expect_config_error(imu_path):
    # 200 Hz * 82 bytes * 10 bits = 164000 bit/s > 115200.
    with pytest.raises(SimConfigError, match='more than 115200 baud'):
        SimWorld.from_config(robot({'path': imu_path, 'rate_hz': 200}))


@pytest.mark.parametrize(
    ('change', 'message'),
    [
        ({'mount': 'turret'}, "imu.mount must be one of gimbal, chassis, got 'turret'"),
        ({'rate': 100}, r"unknown key\(s\) \['rate'\]"),
        ({'mount_rpy': [0, 0]}, r'imu\.mount_rpy must have 3 entries, has 2'),
        ({'baudrate': 115200.5}, r'imu\.baudrate must be integer; got float 115200\.5'),
        ({'path': 7}, r'imu\.path must be string; got int 7'),
        ({'rate_hz': float('nan')}, r'imu\.rate_hz must be finite'),
    ],
)
def test_when_bad_imu_config_expect_config_error(imu_path, change, message):
    with pytest.raises(SimConfigError, match=message):
        SimWorld.from_config(robot({'path': imu_path, **change}))


def test_bus_built_world_carries_the_imu_and_closes_it(imu_path, tmp_path):
    config = robot({'path': imu_path})
    channel = next(iter(config['channels']))
    bus = SimBus(channel, world=config)
    try:
        imu = bus.sim.imu()
        with serial.Serial(imu.path, 115200, timeout=1.0) as port:
            bus.sim.step(20)
            assert len(read_samples(port, 2)) == 2
    finally:
        bus.shutdown()
    assert imu.closed
    assert not os.path.lexists(tmp_path / 'dev' / 'imu')
