"""rm_plugins/Hi220 in rm_robot: HiPNUC frames on a pty -> /imu, /diagnostics, states.

Each test runs the host in-process (private context, parameter_overrides) with the Hi220
plugin reading a pseudo-terminal symlinked at a temporary path, as it reads the
simulator's IMU or /dev/ttyUSB0 on a robot. The test writes frames built with the HiPNUC
encoder into the pty's master side and watches the plugin's topics only.
"""

import math
import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.parameter import Parameter
from rm_base.geometry import quaternion_from_rpy
from rm_base.hardware.protocols import hipnuc
from rm_base.host import RobotHost
from rm_base.plugin import STATE_QOS
from rm_plugins.imu import ImuState
from sensor_msgs.msg import Imu
from std_srvs.srv import SetBool
from support.hosted import HostedPlugins
from support.ros import wait_until
from support.serial_port import Pty, Streamer

from rm_msgs.msg import PluginState

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 10.0  # longest wait for any condition [s]; normally met in well under a second


# Roll 0.1, pitch -0.2 (nose up), yaw 1.0 rad; rates and specific force in SI.
RPY = (0.1, -0.2, 1.0)
GYR = (0.01, -0.02, 0.5)  # [rad/s]
ACC = (0.3, -0.1, 9.7)  # [m/s^2]


def imusol_frame():
    q = quaternion_from_rpy(*RPY)
    return hipnuc.encode_frame(
        hipnuc.encode_imusol(
            acc=ACC, gyr=GYR, mag=(10.0, 0.0, -40.0), euler=RPY, quat=(q.w, q.x, q.y, q.z)
        )
    )


class Harness(HostedPlugins):
    def __init__(self, context, port, **params):
        super().__init__(context, {
            'plugins': ['imu'],
            'imu.type': 'rm_plugins/Hi220',
            'imu.rate': 100.0,
            'imu.port': port,
            'imu.frame_id': 'gimbal_imu',
            'imu.reopen_backoff_min': 0.05,
            'imu.reopen_backoff_max': 0.2,
            'imu.diagnostics_period': 0.1,
            **{f'imu.{k}': v for k, v in params.items()},
        })
        self.imu = self.collect(Imu, '/imu')
        self.diagnostics = self.collect(DiagnosticArray, '/diagnostics')
        self.states = self.collect(PluginState, '/rm_robot/imu/state', STATE_QOS)

    def state(self):
        return ImuState(self.states[-1].state) if self.states else None

    def imu_status(self):
        """The newest /diagnostics status of the plugin as a dict (plus 'level')."""
        return self.diagnostic('rm_robot: imu', self.diagnostics)


@pytest.fixture
def ports():
    """Opens ptys (``ports(path)``); they close after the robot (``run`` depends on this).

    A port closed under a running robot is a device gone: it would log that fault after
    the test.
    """
    opened = []

    def open_port(path):
        opened.append(Pty(path))
        return opened[-1]

    yield open_port
    for port in opened:
        port.close()


@pytest.fixture
def streamer():
    """Streams 0x91 frames into the pty it is started on; stops after the robot."""
    s = Streamer(imusol_frame)
    yield s
    s.stop()
    if s.port is not None:
        s.port.close()


@pytest.fixture
def run(ros_context, ports, streamer):
    # ports and streamer are set up first, so they are torn down after the robot
    made = []

    def make(port, **params):
        made.append(Harness(ros_context, port, **params))
        return made[-1].start()

    yield made, make
    for h in made:
        h.close()


def test_hi220_loads_by_name(run, tmp_path):
    _, make = run
    h = make(str(tmp_path / 'imu'))
    plugin = h.host.plugin('imu')
    assert type(plugin).__module__ == 'rm_plugins.imu.plugin'
    assert h.host.get_parameter('imu.type').value == 'rm_plugins/Hi220'


def test_when_frames_stream_expect_imu_messages_in_si_and_ros_order(run, tmp_path, streamer):
    _, make = run
    path = str(tmp_path / 'imu')
    h = make(path)
    streamer.start(Pty(path))
    assert wait_until(lambda: len(h.imu) >= 5, WAIT)
    msg = h.imu[-1]
    assert msg.header.frame_id == 'gimbal_imu'
    # ROS order (x, y, z, w) of the rotation encoded from RPY (HiPNUC sent w first). The
    # frame carries float32, so agreement is to ~1e-7.
    q = quaternion_from_rpy(*RPY)
    o = msg.orientation
    assert (o.x, o.y, o.z, o.w) == pytest.approx(tuple(q), abs=1e-6)
    v = msg.angular_velocity  # sent in deg/s, published in rad/s
    assert (v.x, v.y, v.z) == pytest.approx(GYR, abs=1e-6)
    a = msg.linear_acceleration  # sent in g, published in m/s^2
    assert (a.x, a.y, a.z) == pytest.approx(ACC, abs=1e-5)
    # Default covariances: diagonal, positive.
    assert msg.orientation_covariance[0] > 0 and msg.orientation_covariance[1] == 0
    assert msg.angular_velocity_covariance[4] > 0
    assert msg.linear_acceleration_covariance[8] > 0
    assert wait_until(lambda: h.state() is ImuState.STREAMING, WAIT)


def test_the_port_name_expands_environment_variables(run, tmp_path, streamer, monkeypatch):
    monkeypatch.setenv('RM_TEST_IMU_DIR', str(tmp_path))
    _, make = run
    h = make('${RM_TEST_IMU_DIR}/imu')
    streamer.start(Pty(str(tmp_path / 'imu')))
    assert wait_until(lambda: len(h.imu) >= 1, WAIT)
    assert wait_until(lambda: h.state() is ImuState.STREAMING, WAIT)
    assert h.states[-1].reason == f'streaming from {tmp_path}/imu'


def test_when_garbage_comes_between_frames_expect_it_skipped_and_counted(run, ports, tmp_path):
    _, make = run
    path = str(tmp_path / 'imu')
    h = make(path)
    port = ports(path)
    assert wait_until(lambda: h.state() is ImuState.NO_DATA, WAIT)  # open, nothing yet
    good = imusol_frame()
    corrupted = bytearray(good)
    corrupted[30] ^= 0x55
    garbage = bytes(range(0x20, 0x40))  # 32 bytes with no sync word
    port.write(garbage + good + bytes(corrupted) + good[:50] + good + garbage + good)
    # Three good frames get through; the corrupted one and the cut-off one fail their
    # CRC (the cut-off one's length runs into the next frame, which is then found by
    # rescanning), and the garbage is discarded.
    assert wait_until(lambda: len(h.imu) == 3, WAIT)
    assert wait_until(lambda: (s := h.imu_status()) is not None and s['frames_ok'] == '3', WAIT)
    status = h.imu_status()
    assert status['crc_errors'] == '2'
    assert int(status['bytes_discarded']) >= 2 * len(garbage)
    assert h.host.plugin('imu').error_count == 0


def test_when_frames_stop_expect_no_data_and_no_stale_imu(run, tmp_path, streamer):
    _, make = run
    path = str(tmp_path / 'imu')
    h = make(path, data_timeout=0.1, silence_reopen=0.0)
    streamer.start(Pty(path))
    assert wait_until(lambda: h.state() is ImuState.STREAMING, WAIT)
    streamer.make_frame = lambda: b''  # the device stops sending; the port stays open
    assert wait_until(lambda: h.state() is ImuState.NO_DATA, WAIT)
    assert h.states[-1].reason == f'no valid frame from {path} within 0.100 s'
    count = len(h.imu)
    # Nothing is published while there is no new frame: wait 3 data timeouts worth of
    # diagnostics and check no /imu message came (the diagnostics prove the plugin ran).
    seen = len(h.diagnostics)
    assert wait_until(lambda: len(h.diagnostics) >= seen + 3, WAIT)
    assert len(h.imu) == count
    assert h.imu_status()['level'] == b'\x01'  # WARN


def counted_frame(device_ms):
    q = quaternion_from_rpy(*RPY)
    return hipnuc.encode_frame(hipnuc.encode_imusol(
        acc=ACC, gyr=GYR, mag=(10.0, 0.0, -40.0), euler=RPY, quat=(q.w, q.x, q.y, q.z),
        system_time_ms=device_ms,
    ))


def test_when_frames_queued_expect_them_stamped_when_the_device_took_them(run, ports, tmp_path):
    _, make = run
    path = str(tmp_path / 'imu')
    h = make(path)
    port = ports(path)
    assert wait_until(lambda: h.state() is ImuState.NO_DATA, WAIT)
    # 0.3 s of frames as they come, 5 ms apart, the counter in real milliseconds...
    start = time.monotonic()
    for k in range(60):
        time.sleep(max(0.0, start + 0.005 * k - time.monotonic()))
        port.write(counted_frame(round(1e3 * (time.monotonic() - start))))
    assert wait_until(lambda: len(h.imu) == 60, WAIT)
    # ...then 20 frames the device took over 100 ms arrive at once (the serial buffer
    # of a reader that was starved)
    time.sleep(0.1)
    last_ms = round(1e3 * (time.monotonic() - start))
    port.write(b''.join(counted_frame(last_ms - 5 * (19 - k)) for k in range(20)))
    assert wait_until(lambda: len(h.imu) == 80, WAIT)
    stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in h.imu[60:]]
    # 95 ms apart as taken (a few ms off for the writer's own lateness), not all at receipt
    assert stamps == sorted(stamps)
    assert stamps[-1] - stamps[0] == pytest.approx(0.095, abs=0.02)


def test_when_the_port_vanishes_expect_no_port_then_recovery(run, tmp_path, streamer):
    _, make = run
    path = str(tmp_path / 'imu')
    h = make(path)
    streamer.start(Pty(path))
    assert wait_until(lambda: h.state() is ImuState.STREAMING, WAIT)

    old, streamer.port = streamer.port, None
    old.close()  # unplugged: reads fail, the path disappears
    assert wait_until(lambda: h.state() is ImuState.NO_PORT, WAIT)
    assert 'reopening with back-off' in h.states[-1].reason
    assert wait_until(lambda: (s := h.imu_status()) is not None and s['level'] == b'\x02', WAIT)

    count = len(h.imu)
    streamer.port = Pty(path)  # plugged back in
    assert wait_until(lambda: h.state() is ImuState.STREAMING, WAIT)
    assert wait_until(lambda: len(h.imu) > count, WAIT)
    assert wait_until(lambda: h.imu_status()['port_losses'] == '1', WAIT)


def test_when_disabled_expect_the_port_closed_and_passive(run, tmp_path, streamer):
    _, make = run
    path = str(tmp_path / 'imu')
    h = make(path)
    streamer.start(Pty(path))
    assert wait_until(lambda: h.state() is ImuState.STREAMING, WAIT)
    client = h.probe.create_client(SetBool, '/rm_robot/imu/enable')
    assert client.wait_for_service(timeout_sec=WAIT)
    future = client.call_async(SetBool.Request(data=False))
    assert wait_until(future.done, WAIT) and future.result().success
    assert wait_until(lambda: h.state() is ImuState.PASSIVE and not h.states[-1].enabled, WAIT)
    assert not h.host.plugin('imu').reader.running
    count = len(h.imu)
    # Frames keep coming into the pty, but nothing is read or published any more.
    assert not wait_until(lambda: len(h.imu) > count + 1, 0.3)


@pytest.mark.parametrize(
    ('params', 'message'),
    [
        ({'port': '${RM_SURELY_UNSET_VARIABLE}/imu'}, 'unset environment variable'),
        ({'reopen_backoff_min': 1.0, 'reopen_backoff_max': 0.5}, 'reopen_backoff_max'),
        ({'mount_rpy': [0.0, 0.0]}, 'must have 3 entries'),
    ],
    ids=['unset-variable', 'backoff-order', 'mount-length'],
)
def test_a_bad_config_is_one_clear_error(ros_context, tmp_path, params, message):
    overrides = {
        'plugins': ['imu'],
        'imu.type': 'rm_plugins/Hi220',
        'imu.port': str(tmp_path / 'imu'),
        **{f'imu.{k}': v for k, v in params.items()},
    }
    with pytest.raises(Exception, match=message):
        RobotHost(
            context=ros_context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )


def test_euler_only_legacy_frames_give_an_orientation(run, ports, tmp_path):
    _, make = run
    path = str(tmp_path / 'imu')
    h = make(path)
    port = ports(path)
    assert wait_until(lambda: h.state() is ImuState.NO_DATA, WAIT)
    # Legacy 0xD0 Euler (0.01 deg pitch/roll, 0.1 deg yaw) + 0xB0 gyro (0.1 deg/s).
    payload = hipnuc.encode_legacy(euler=(0.0, 0.0, math.radians(30.0)), gyr=(0, 0, 0.1),
                                   user_id=7)
    port.write(hipnuc.encode_frame(payload))
    assert wait_until(lambda: len(h.imu) == 1, WAIT)
    # the unit's user id (0x90) is reported on /diagnostics
    assert wait_until(lambda: (s := h.imu_status()) is not None and s['user_id'] == '7', WAIT)
    o = h.imu[0].orientation
    assert (o.z, o.w) == pytest.approx((math.sin(math.radians(15)), math.cos(math.radians(15))))
    assert h.imu[0].linear_acceleration_covariance[0] == -1.0  # not provided
    # A unit that appends an item this driver cannot read (0x83): what came before it
    # is published, and /diagnostics counts the frames whose tail was left unread.
    port.write(hipnuc.encode_frame(payload + b'\x83' + bytes(60)))
    assert wait_until(lambda: len(h.imu) == 2, WAIT)
    assert wait_until(
        lambda: (s := h.imu_status()) is not None
        and s['frames with unread items'] == '1 (item 0x83)', WAIT,
    )


@pytest.mark.slow
def test_on_the_simulator_imu_follows_the_turning_gimbal():
    # The whole simulated robot (standard.yaml + standard_sim.yaml) with only the Hi220
    # plugin: the simulated IMU on the gimbal writes HiPNUC 0x91 frames into its pty. The
    # test turns the yaw joint at 2 rad/s (MODE_VELOCITY on /actuator_cmd) and compares
    # /imu with the simulator's ground truth. The pitch is held level: unpowered, the
    # nose-heavy gimbal would tip over while the yaw spins up, and tilt /imu's gravity.
    from support.robot import SimRobot

    from rm_msgs.msg import ActuatorCmd

    with SimRobot(plugins=['imu']) as robot:
        robot.subscribe('/imu', Imu)
        robot.publish(
            '/actuator_cmd',
            ActuatorCmd(
                name=['yaw', 'pitch'],
                mode=[ActuatorCmd.MODE_VELOCITY, ActuatorCmd.MODE_POSITION],
                position=[0.0, 0.0],
                velocity=[2.0, 0.0],
                effort=[0.0, 0.0],
                kp=[0.0, 0.0],
                kd=[0.0, 0.0],
            ),
            rate_hz=100.0,
        )
        world = robot.world

        def truth():
            with world.lock:
                return world.body.yaw + world.body.gimbal_yaw, world.body.yaw_joint.velocity

        assert robot.wait_until(lambda: abs(truth()[1] - 2.0) < 0.1, WAIT)

        def agrees():
            msg = robot.latest('/imu')
            if msg is None:
                return False
            yaw, rate = truth()
            q = msg.orientation
            measured = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
            # The message is up to one frame (2.5 ms at 400 Hz) plus delivery behind the
            # truth: at 2 rad/s, 0.05 rad covers 25 ms of lag.
            return (
                msg.header.frame_id == 'gimbal_imu'
                and abs(math.remainder(measured - yaw, 2 * math.pi)) < 0.05
                and abs(msg.angular_velocity.z - rate) < 0.1
                and abs(msg.linear_acceleration.z - 9.80665) < 0.1  # +g at rest, in m/s^2
            )

        assert robot.wait_until(agrees, WAIT)
