"""Hi220 gyro bias at standstill: ~/<plugin>/calibrate_gyro over a pty of HiPNUC frames.

A still IMU whose gyro reads a small constant rate gets that rate as its bias: the
published rates read 0 from then on, the calibration file keeps it, and a plugin started
again from the file subtracts it from its first message. A shaking or turning IMU, or one
that sends nothing, is refused with the reason. Wall-clock smoke tests: the window is
0.3 s and every wait is bounded by WAIT.
"""

import itertools

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rm_base.config.calibration import CalibrationFile
from rm_base.hardware.protocols import hipnuc
from rm_plugins.imu import ImuState
from sensor_msgs.msg import Imu
from std_srvs.srv import Trigger
from support.hosted import HostedPlugins
from support.ros import wait_until
from support.serial_port import Pty, Streamer

from rm_msgs.msg import PluginState

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 10.0  # longest wait for any condition [s]; normally met in well under a second
NOT_ENOUGH = 'refused: not enough IMU data'
BIAS = (0.004, -0.006, 0.002)  # [rad/s] what the still sensor reads


def frames(rates):
    """A frame maker cycling through rates (x, y, z) [rad/s] of a level IMU."""
    cycle = itertools.cycle(rates)

    def make():
        return hipnuc.encode_frame(hipnuc.encode_imusol(
            acc=(0.0, 0.0, 9.8), gyr=next(cycle), mag=(0.0, 0.0, 0.0), euler=(0.0, 0.0, 0.0),
            quat=(1.0, 0.0, 0.0, 0.0),
        ))
    return make


class Harness(HostedPlugins):
    def __init__(self, context, port, calibration):
        super().__init__(context, {
            'plugins': ['imu'],
            'imu.type': 'rm_plugins/Hi220',
            'imu.port': port,
            'imu.diagnostics_period': 0.1,
            'imu.calibration.file': calibration,
            'imu.calibration.duration': 0.3,
        })
        self.imu = self.collect(Imu, '/imu')
        self.diagnostics = self.collect(DiagnosticArray, '/diagnostics')
        self.states = self.collect(PluginState, '/rm_robot/imu/state')
        self.plugin = self.host.plugin('imu')

    def streaming_for(self, seconds):
        """Wait until the plugin has streamed for a window and more."""
        assert wait_until(lambda: self.plugin.state is ImuState.STREAMING, WAIT)
        count = len(self.imu)
        assert wait_until(lambda: len(self.imu) >= count + round(seconds / 0.005), WAIT)

    def calibrate(self, call):
        """call() -> (ok, message), called again while the window is not full.

        A pause of the whole VM longer than the IMU's timeout (0.1 s) leaves a hole in the
        window of rates; the plugin rightly answers NOT_ENOUGH until it is full again.
        """
        answer = None

        def judged():
            nonlocal answer
            answer = call()
            return not answer[1].startswith(NOT_ENOUGH)

        assert wait_until(judged, WAIT), answer
        return answer


@pytest.fixture
def rig(ros_context, tmp_path):
    made, streamers = [], []

    def make(rates):
        port = str(tmp_path / 'imu')
        h = Harness(ros_context, port, str(tmp_path / 'calibration.yaml')).start()
        made.append(h)
        streamer = Streamer(frames(rates))
        streamers.append(streamer)
        streamer.start(Pty(port))
        return h

    yield make, tmp_path / 'calibration.yaml'
    # the robot first: a port closed under it is a device gone, a fault it would log
    for h in made:
        h.close()
    for s in streamers:
        s.stop()
        s.port.close()


def rate(msg):
    v = msg.angular_velocity
    return (v.x, v.y, v.z)


def test_a_still_imu_gets_its_bias_subtracted_and_kept_for_the_next_start(rig):
    make, path = rig
    h = make([BIAS])
    h.streaming_for(0.4)
    assert rate(h.imu[-1]) == pytest.approx(BIAS, abs=1e-6)  # float32 on the wire
    client = h.probe.create_client(Trigger, '/rm_robot/imu/calibrate_gyro')
    assert client.wait_for_service(timeout_sec=WAIT)

    def call():
        future = client.call_async(Trigger.Request())
        assert wait_until(future.done, WAIT)
        reply = future.result()
        return reply.success, reply.message

    ok, message = h.calibrate(call)
    assert ok, message
    assert message.startswith('gyro bias (0.00400, -0.00600, 0.00200) rad/s from ')
    assert message.endswith(f'over 0.3 s, saved to {path}')
    count = len(h.imu)
    assert wait_until(lambda: len(h.imu) > count + 2, WAIT)
    assert rate(h.imu[-1]) == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
    assert wait_until(
        lambda: (h.diagnostic('rm_robot: imu', h.diagnostics) or {}).get('gyro bias [rad/s]')
        == '0.00400, -0.00600, 0.00200', WAIT,
    )
    saved = CalibrationFile(str(path)).entries('imu', ('gyro_bias',))['imu']['gyro_bias']
    assert saved == pytest.approx(BIAS, abs=1e-6)
    h.close()
    again = make([BIAS])
    assert wait_until(lambda: len(again.imu) > 0, WAIT)
    assert rate(again.imu[0]) == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)


@pytest.mark.parametrize(
    ('rates', 'message'),
    [
        ([(0.0, 0.0, 0.1), (0.0, 0.0, -0.1)], 'refused: moving: the rate varies by 0.1000 rad/s'),
        ([(0.0, 0.0, 0.3)], 'refused: turning: mean rate 0.3000 rad/s, more than a bias'),
    ],
    ids=['shaking', 'turning'],
)
def test_a_moving_imu_is_refused_and_keeps_no_bias(rig, rates, message):
    make, path = rig
    h = make(rates)
    h.streaming_for(0.4)
    ok, reply = h.calibrate(h.plugin.calibrate_gyro)
    assert not ok and reply.startswith(message)
    assert h.plugin.gyro_bias is None and not path.exists()


def test_without_data_the_calibration_is_refused(ros_context, tmp_path):
    h = Harness(ros_context, str(tmp_path / 'imu'), str(tmp_path / 'c.yaml')).start()
    try:
        assert wait_until(lambda: h.plugin.state is ImuState.NO_PORT, WAIT)
        ok, reply = h.plugin.calibrate_gyro()
        assert not ok and reply.startswith('refused: the IMU is NO_PORT, not STREAMING (')
    finally:
        h.close()
