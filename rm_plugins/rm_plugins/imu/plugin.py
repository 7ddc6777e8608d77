"""Hi220: a HiPNUC IMU on a serial port -> sensor_msgs/Imu (REP 103, SI).

A ``SerialReader`` owns the port while the plugin is enabled: its thread opens the port
(a pyserial URL; ``~`` and ``${VAR}`` expanded, so the simulator's
``/tmp/rm_sim_${ROS_DOMAIN_ID}/imu`` works); the control loop reads it after every tick
(outside a loop, the thread does), decodes HiPNUC frames (0x91 and the legacy items) and
publishes every sample at once, so no sample waits for a plugin tick. A sample
is stamped when the device took it: its ``system_time_ms`` counter mapped to ROS time by
``DeviceClock`` (the offset of the fastest frame of the last 2 s), so frames that queued
while the reader was starved keep their age instead of looking fresh; a frame without
a moving counter is stamped at its receipt. The plugin's ``run()`` only decides the
state from what the reader reports and publishes the counters on /diagnostics; it never
touches the port.

States (``ImuState``, a serial device's ``LinkState``):

- PASSIVE: disabled; the port is closed.
- NO_PORT: the port cannot be opened, or it failed or went silent and is being reopened
  with back-off (the reason says why).
- NO_DATA: the port is open but no valid frame arrived within ``data_timeout``; nothing is
  published then, so a reader of /imu never gets old orientation as fresh.
- STREAMING: valid frames arrive; each becomes one sensor_msgs/Imu.

Bad bytes, CRC failures and undecodable frames are skipped (the parser resynchronises)
and counted on /diagnostics (status ``rm_robot: <plugin>``), never fatal.

Gyro bias: ``~/<plugin>/calibrate_gyro`` (std_srvs/Trigger) takes the mean rate of the
last ``calibration.duration`` seconds as the bias, if they show the IMU at rest
(``rm_plugins.imu.gyro_bias``), subtracts it from every published rate from then on and
keeps it in ``calibration.file`` (read again at start-up). The orientation is the
unit's own fusion and is not changed.
"""

from __future__ import annotations

import math
import threading

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.time import Time
from rm_base.config.calibration import CalibrationError, CalibrationFile, finite_values
from rm_base.hardware.device_clock import DeviceClock
from rm_base.hardware.protocols.hipnuc import HipnucParser, ImuSample
from rm_base.plugin import PluginBase, PluginParams
from sensor_msgs.msg import Imu
from std_srvs.srv import Trigger

from rm_plugins.imu.conversion import Mounting, reading_from_sample
from rm_plugins.imu.gyro_bias import GyroWindow, NotAtRestError, RestLimits, bias_at_rest
from rm_plugins.imu.message import imu_message
from rm_plugins.serial.device import DeviceLink, LinkState, link_status, read_serial_settings
from rm_plugins.serial.reader import ReaderStats

_NS_PER_S = 1_000_000_000

#: Default covariances (row-major 3x3, diagonal): Hi220 datasheet-level noise, roughly
#: 0.5 deg roll/pitch and 1 deg yaw, 0.1 deg/s gyro, 10 mg accelerometer (1 sigma).
_ORIENTATION_COV = (7.6e-5, 0.0, 0.0, 0.0, 7.6e-5, 0.0, 0.0, 0.0, 3.0e-4)
_RATE_COV = (3.0e-6, 0.0, 0.0, 0.0, 3.0e-6, 0.0, 0.0, 0.0, 3.0e-6)
_ACCEL_COV = (1.0e-2, 0.0, 0.0, 0.0, 1.0e-2, 0.0, 0.0, 0.0, 1.0e-2)


#: The Hi220's states are a serial device's (see ``rm_plugins.serial.device.LinkState``).
ImuState = LinkState


class Hi220(PluginBase):
    """HiPNUC Hi220 IMU over serial, published as sensor_msgs/Imu.

    Parameters (under ``<name>.``):
        port: pyserial URL or device path; ``${VAR}`` and ``~`` expanded (required).
        baudrate: [bit/s], 115200.
        frame_id: frame of the published data, ``imu_link``.
        topic: sensor_msgs/Imu output, ``imu``.
        mount_rpy: (roll, pitch, yaw) [rad] of the sensor's axes in frame_id; the data is
            rotated into frame_id. (0, 0, 0): published in the sensor's axes.
        orientation_covariance, angular_velocity_covariance,
        linear_acceleration_covariance: row-major 3x3 [rad², (rad/s)², (m/s²)²] in the
            sensor's axes (rotated with the data).
        data_timeout: no valid frame this long -> NO_DATA [s], 0.1.
        read_timeout: longest blocking read of the reader thread [s], 0.02.
        reopen_backoff_min / reopen_backoff_max: wait before reopening a lost port,
            doubling from min to max [s], 0.1 / 2.0.
        silence_reopen: reopen an open port silent this long [s], 1.0; 0 = never.
        diagnostics_period: period of the /diagnostics status [s], 1.0.
        calibration.file: where calibrate_gyro keeps the bias (``imu.<plugin>.gyro_bias``)
            and where it is read at start-up; empty: the bias lasts until the node stops.
        calibration.duration / max_rate / max_spread: the window averaged [s], 1.0; the
            largest mean [rad/s], 0.05, and standard deviation [rad/s], 0.02, per axis of
            an IMU at rest.
    """

    State = ImuState

    def on_init(self) -> None:
        """Read the parameters, create the publishers and the (not yet started) reader."""
        p = self.params
        self._settings = settings = read_serial_settings(
            p, baudrate=115200, data_timeout=0.1, silence_reopen=1.0
        )
        self.port, self.baudrate = settings.port, settings.baudrate
        self.frame_id = p.string('frame_id', 'imu_link', description='frame_id of /imu')
        topic = p.string('topic', 'imu', description='sensor_msgs/Imu output topic')
        mount = p.vector3(
            'mount_rpy',
            (0.0, 0.0, 0.0),
            unit='rad',
            description="roll, pitch, yaw of the sensor's axes in frame_id",
        )
        self.mounting = Mounting(mount)
        covariance = {
            name: self.mounting.rotate_covariance(
                p.double_array(
                    name,
                    default,
                    length=9,
                    unit=unit,
                    description=f'{what}, row-major 3x3, sensor axes',
                )
            )
            for name, default, unit, what in (
                ('orientation_covariance', _ORIENTATION_COV, 'rad^2', 'orientation covariance'),
                (
                    'angular_velocity_covariance',
                    _RATE_COV,
                    '(rad/s)^2',
                    'angular velocity covariance',
                ),
                (
                    'linear_acceleration_covariance',
                    _ACCEL_COV,
                    '(m/s^2)^2',
                    'acceleration covariance',
                ),
            )
        }
        self.orientation_covariance = covariance['orientation_covariance']
        self.angular_velocity_covariance = covariance['angular_velocity_covariance']
        self.linear_acceleration_covariance = covariance['linear_acceleration_covariance']
        self._clock = self.node.get_clock()
        # a new message per sample: the gimbal and chassis get it with no copy
        self._publisher = self.create_publisher(Imu, topic, 10, hand_over=True)
        self._diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._lock = threading.Lock()
        self._device_clock = DeviceClock()
        self._published = 0
        self._user_id: int | None = None  # the unit's user id (0x90), when it sends it
        # frames whose tail was not read (an item of unknown length), and the last such tag
        self._unread_frames = 0
        self._unread_tag: int | None = None
        self._next_diagnostics_ns: int | None = None
        self._report_published = 0
        self._report_ns: int | None = None
        self._report_bad = 0
        self._read_calibration(p)
        self._link = DeviceLink(
            self, settings, self._on_sample, parser=HipnucParser(), name='hipnuc'
        )
        self.reader = self._link.reader
        self._calibrate_service = self.node.create_service(
            Trigger, f'~/{self.name}/calibrate_gyro', self._on_calibrate_gyro
        )

    def _read_calibration(self, p: PluginParams) -> None:
        c = p.group('calibration')
        path = c.string('file', '', description='where calibrate_gyro keeps the gyro bias; '
                        'empty: the bias lasts until the node stops')
        self._rest = RestLimits(
            duration_s=c.double('duration', 1.0, gt=0.0, unit='s',
                                description='calibrate_gyro averages this much of the rate'),
            max_rate=c.double('max_rate', 0.05, gt=0.0, unit='rad/s',
                              description='a larger mean rate is a turn, not a bias'),
            max_spread=c.double('max_spread', 0.02, gt=0.0, unit='rad/s',
                                description='a larger standard deviation is motion'),
        )
        self._gyro_window = GyroWindow(self._rest.duration_s)
        self._calibration = CalibrationFile(path) if path else None
        self.gyro_bias: tuple[float, float, float] | None = None
        if self._calibration is not None:
            entry = self._calibration.entries('imu', ('gyro_bias',)).get(self.name, {})
            if 'gyro_bias' in entry:  # calibrate_gyro refuses a bias beyond max_rate
                x, y, z = finite_values(
                    f'{self._calibration.path}: imu.{self.name}.gyro_bias',
                    entry['gyro_bias'], 3, limit=self._rest.max_rate,
                )
                self.gyro_bias = (x, y, z)
                self.logger.info(
                    f'gyro bias ({x:.5f}, {y:.5f}, {z:.5f}) rad/s from {self._calibration.path}'
                )

    # -- lifecycle --------------------------------------------------------------------------

    def on_enable(self) -> None:
        """Start the reader (its thread opens the port)."""
        self._device_clock = DeviceClock()  # the reader is not running
        with self._lock:
            self._gyro_window.clear()  # a bias is averaged over this run's samples only
        self._link.start()

    def on_disable(self) -> None:
        """Stop the reader and close the port."""
        self._link.stop()

    # -- tick -------------------------------------------------------------------------------

    def update(self, now: Time, dt: float) -> None:
        """Decide the state from the reader's report; publish /diagnostics when due."""
        now_ns = now.nanoseconds
        state, reason, stats = self._link.decide(now_ns)
        self.transition(state, reason)
        if self._next_diagnostics_ns is None or now_ns >= self._next_diagnostics_ns:
            period_ns = round(self._settings.diagnostics_period * _NS_PER_S)
            self._next_diagnostics_ns = now_ns + period_ns
            self._publish_diagnostics(now, stats)

    # -- reading thread (the loop's, or the reader's) ---------------------------------------

    def _on_sample(self, sample: ImuSample) -> None:
        """Convert and publish one sample (called in the reading thread)."""
        if sample.user_id is not None and sample.user_id != self._user_id:
            with self._lock:
                self._user_id = sample.user_id
        if sample.unread_tag is not None:
            self._note_unread(sample.unread_tag)
        reading = reading_from_sample(sample, self.mounting, self.gyro_bias)
        if (
            reading.orientation is None
            and reading.angular_velocity is None
            and reading.linear_acceleration is None
        ):
            return  # e.g. a pressure-only frame: nothing for sensor_msgs/Imu
        now_ns = self._clock.now().nanoseconds
        stamp_ns = now_ns
        if sample.system_time_ms is not None:
            stamp_ns = self._device_clock.stamp_ns(sample.system_time_ms, now_ns)
        msg = imu_message(
            reading, stamp_ns, self.frame_id,
            (self.orientation_covariance, self.angular_velocity_covariance,
             self.linear_acceleration_covariance),
        )
        self._publisher.publish(msg)
        self._link.received(now_ns)
        with self._lock:
            self._published += 1
            if sample.gyr is not None:
                self._gyro_window.add(stamp_ns, sample.gyr)

    # -- calibration (executor thread) ------------------------------------------------------

    def _on_calibrate_gyro(
        self, request: Trigger.Request, response: Trigger.Response
    ) -> Trigger.Response:
        response.success, response.message = self.calibrate_gyro()
        return response

    def calibrate_gyro(self) -> tuple[bool, str]:
        """~/<plugin>/calibrate_gyro: the bias from the last window at rest, kept.

        Returns:
            Whether the bias was set, and what it is or why not.
        """
        if self.state is not ImuState.STREAMING:
            message = f'refused: the IMU is {self.state.name}, not STREAMING ({self.reason})'
            self.logger.warning(f'calibrate_gyro {message}')
            return False, message
        with self._lock:
            samples = self._gyro_window.snapshot()
        try:
            bias = bias_at_rest(samples, self._rest)
        except NotAtRestError as err:
            self.logger.warning(f'calibrate_gyro refused: {err}')
            return False, f'refused: {err}'
        self.gyro_bias = bias
        kept = 'until the node stops (no calibration.file)'
        if self._calibration is not None:
            try:
                self._calibration.write('imu', self.name, {'gyro_bias': list(bias)})
            except CalibrationError as err:
                kept = f'until the node stops: {err}'
            else:
                kept = f'saved to {self._calibration.path}'
        x, y, z = bias
        message = (
            f'gyro bias ({x:.5f}, {y:.5f}, {z:.5f}) rad/s from {len(samples)} samples over '
            f'{self._rest.duration_s:g} s, {kept}'
        )
        self.logger.info(message)
        return True, message

    def _note_unread(self, tag: int) -> None:
        with self._lock:
            first = self._unread_tag != tag
            self._unread_frames += 1
            self._unread_tag = tag
        if first:
            self.logger.warning(
                f'frames carry item 0x{tag:02X}, which this driver cannot read: the items '
                'before it are used, it and the rest of each such frame are ignored '
                '(configure the unit to send 0x91)'
            )

    # -- diagnostics ------------------------------------------------------------------------

    def _publish_diagnostics(self, now: Time, stats: ReaderStats) -> None:
        state = LinkState(self.state.value)
        with self._lock:
            published, user_id = self._published, self._user_id
            unread_frames, unread_tag = self._unread_frames, self._unread_tag
        now_ns = now.nanoseconds
        rate = math.nan
        if self._report_ns is not None and now_ns > self._report_ns:
            rate = (published - self._report_published) * _NS_PER_S / (now_ns - self._report_ns)
        new_bad = stats.bad_frames + stats.sample_errors - self._report_bad
        self._report_ns, self._report_published = now_ns, published
        self._report_bad = stats.bad_frames + stats.sample_errors
        status = link_status(
            f'{self.node.get_name()}: {self.name}', self._settings, state, stats,
            reason=self.reason, new_bad=new_bad,
            values={
                'published': published, 'rate [Hz]': f'{rate:.1f}',
                'user_id': 'not sent' if user_id is None else user_id,
                'gyro bias [rad/s]': (
                    'none' if self.gyro_bias is None
                    else ', '.join(f'{v:.5f}' for v in self.gyro_bias)
                ),
                'frames with unread items': (
                    0 if unread_tag is None else f'{unread_frames} (item 0x{unread_tag:02X})'
                ),
            },
        )
        msg = DiagnosticArray()
        msg.header.stamp = now.to_msg()
        msg.status = [status]
        self._diagnostics.publish(msg)
