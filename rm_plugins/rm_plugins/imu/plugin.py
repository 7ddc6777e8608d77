"""Hi220: a HiPNUC IMU on a serial port -> sensor_msgs/Imu (REP 103, SI).

A reader thread (``SerialReader``) owns the port while the plugin is enabled: it opens
the port (a pyserial URL; ``~`` and ``${VAR}`` expanded, so the simulator's
``/tmp/rm_sim_${ROS_DOMAIN_ID}/imu`` works), decodes HiPNUC frames (0x91 and the legacy
items) and publishes every sample at once, so no sample waits for a plugin tick. A sample
is stamped when the device took it: its ``system_time_ms`` counter mapped to ROS time by
``DeviceClock`` (the offset of the fastest frame of the last 2 s), so frames that queued
while the reader was starved keep their age instead of looking fresh; a frame without
a moving counter is stamped at its receipt. The plugin's ``run()`` only decides the
state from what the reader reports and publishes the counters on /diagnostics; it never
touches the port.

States (``ImuState``), all decided in ``_decide``:

- PASSIVE: disabled; the port is closed.
- NO_PORT: the port cannot be opened, or it failed or went silent and is being reopened
  with back-off (the reason says why).
- NO_DATA: the port is open but no valid frame arrived within ``data_timeout``; nothing is
  published then, so a reader of /imu never gets old orientation as fresh.
- STREAMING: valid frames arrive; each becomes one sensor_msgs/Imu.

Bad bytes, CRC failures and undecodable frames are skipped (the parser resynchronises)
and counted on /diagnostics (status ``rm_robot: <plugin>``), never fatal.
"""

from __future__ import annotations

import math
import os
import threading
from enum import IntEnum

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rm_base.hardware.device_clock import DeviceClock
from rm_base.hardware.protocols.hipnuc import ImuSample
from rm_base.plugin import PluginBase, PluginConfigError
from sensor_msgs.msg import Imu

from rm_plugins.imu.conversion import Mounting, reading_from_sample
from rm_plugins.imu.message import imu_message
from rm_plugins.imu.reader import ReaderStats, SerialReader

_NS_PER_S = 1_000_000_000

#: Default covariances (row-major 3x3, diagonal): Hi220 datasheet-level noise, roughly
#: 0.5 deg roll/pitch and 1 deg yaw, 0.1 deg/s gyro, 10 mg accelerometer (1 sigma).
_ORIENTATION_COV = (7.6e-5, 0.0, 0.0, 0.0, 7.6e-5, 0.0, 0.0, 0.0, 3.0e-4)
_RATE_COV = (3.0e-6, 0.0, 0.0, 0.0, 3.0e-6, 0.0, 0.0, 0.0, 3.0e-6)
_ACCEL_COV = (1.0e-2, 0.0, 0.0, 0.0, 1.0e-2, 0.0, 0.0, 0.0, 1.0e-2)


class ImuState(IntEnum):
    """States of the Hi220 plugin (see the module docstring)."""

    PASSIVE = 0
    NO_PORT = 1
    NO_DATA = 2
    STREAMING = 3


_LEVELS = {
    ImuState.PASSIVE: DiagnosticStatus.OK,
    ImuState.NO_PORT: DiagnosticStatus.ERROR,
    ImuState.NO_DATA: DiagnosticStatus.WARN,
    ImuState.STREAMING: DiagnosticStatus.OK,
}


def expand_port(port: str) -> str:
    """Expand ``${VAR}`` (and ``~`` in a plain path) in a port name.

    Raises:
        PluginConfigError: the name is empty or uses an unset environment variable.
    """
    expanded = os.path.expandvars(port.strip())
    if '://' not in expanded:
        expanded = os.path.expanduser(expanded)
    if not expanded or '$' in expanded:
        raise PluginConfigError(f'port {port!r} is empty or uses an unset environment variable')
    return expanded


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
    """

    State = ImuState

    def on_init(self) -> None:
        """Read the parameters, create the publishers and the (not yet started) reader."""
        p = self.params
        self.port = expand_port(
            p.string(
                'port',
                description='serial port: device path or pyserial URL; ${VAR} and ~ are expanded',
            )
        )
        self.baudrate = p.integer('baudrate', 115200, description='baud rate', unit='bit/s', gt=0)
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
        self.data_timeout = p.double(
            'data_timeout', 0.1, unit='s', gt=0.0, description='no valid frame this long -> NO_DATA'
        )
        read_timeout = p.double(
            'read_timeout',
            0.02,
            unit='s',
            gt=0.0,
            le=1.0,
            description='longest blocking read in the reader thread',
        )
        backoff_min = p.double(
            'reopen_backoff_min',
            0.1,
            unit='s',
            gt=0.0,
            description='first wait before reopening a lost port',
        )
        backoff_max = p.double(
            'reopen_backoff_max',
            2.0,
            unit='s',
            gt=0.0,
            description='longest wait between reopen attempts',
        )
        if backoff_max < backoff_min:
            raise PluginConfigError(
                f'reopen_backoff_max ({backoff_max} s) is below reopen_backoff_min '
                f'({backoff_min} s)'
            )
        silence = p.double(
            'silence_reopen',
            1.0,
            unit='s',
            ge=0.0,
            description='reopen a port silent this long; 0 = never',
        )
        self.diagnostics_period = p.double(
            'diagnostics_period',
            1.0,
            unit='s',
            gt=0.0,
            description='period of the /diagnostics status',
        )

        self._clock = self.node.get_clock()
        # a new message per sample: the gimbal and chassis get it with no copy
        self._publisher = self.create_publisher(Imu, topic, 10, hand_over=True)
        self._diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._lock = threading.Lock()
        self._last_sample_ns: int | None = None  # receipt of the latest sample
        self._device_clock = DeviceClock()
        self._published = 0
        self._next_diagnostics_ns: int | None = None
        self._report_published = 0
        self._report_ns: int | None = None
        self._report_bad = 0
        # read after the loop's ticks, in its idle time (no loop: the reader's own pace)
        self.reader = SerialReader(
            self.port,
            self.baudrate,
            self._on_sample,
            self.logger,
            read_timeout=read_timeout,
            backoff_min=backoff_min,
            backoff_max=backoff_max,
            silence_reopen=silence,
            paced=self.in_loop,
        )
        if self.reader.paced:
            self.after_tick(self.reader.wake)

    # -- lifecycle --------------------------------------------------------------------------

    def on_enable(self) -> None:
        """Start the reader thread (it opens the port)."""
        with self._lock:
            self._last_sample_ns = None
        self._device_clock = DeviceClock()  # the reader thread is not running
        self.reader.start()

    def on_disable(self) -> None:
        """Stop the reader thread and close the port."""
        if not self.reader.stop():
            self.logger.error(f'the reader of {self.port} did not stop')

    # -- tick -------------------------------------------------------------------------------

    def update(self, now, dt: float) -> None:
        """Decide the state from the reader's report; publish /diagnostics when due."""
        now_ns = now.nanoseconds
        stats = self.reader.stats()
        state, reason = self._decide(now_ns, stats)
        self.transition(state, reason)
        if self._next_diagnostics_ns is None or now_ns >= self._next_diagnostics_ns:
            self._next_diagnostics_ns = now_ns + round(self.diagnostics_period * _NS_PER_S)
            self._publish_diagnostics(now, stats)

    def _decide(self, now_ns: int, stats: ReaderStats) -> tuple[ImuState, str]:
        """The one place that chooses the state (called every tick while enabled)."""
        with self._lock:
            last_ns = self._last_sample_ns
        if not stats.port_open:
            why = stats.last_error or 'opening'
            return ImuState.NO_PORT, f'{why}; reopening with back-off'
        if last_ns is None:
            return ImuState.NO_DATA, f'{self.port} open, no valid frame yet'
        if now_ns - last_ns > self.data_timeout * _NS_PER_S:
            return (
                ImuState.NO_DATA,
                f'no valid frame from {self.port} within {self.data_timeout:.3f} s',
            )
        return ImuState.STREAMING, f'streaming from {self.port}'

    # -- reader thread ----------------------------------------------------------------------

    def _on_sample(self, sample: ImuSample) -> None:
        """Convert and publish one sample (called in the reader thread)."""
        reading = reading_from_sample(sample, self.mounting)
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
        with self._lock:
            self._last_sample_ns = now_ns
            self._published += 1

    # -- diagnostics ------------------------------------------------------------------------

    def _publish_diagnostics(self, now, stats: ReaderStats) -> None:
        state, reason = ImuState(self.state.value), self.reason
        with self._lock:
            published = self._published
        now_ns = now.nanoseconds
        rate = math.nan
        if self._report_ns is not None and now_ns > self._report_ns:
            rate = (published - self._report_published) * _NS_PER_S / (now_ns - self._report_ns)
        new_bad = stats.bad_frames + stats.sample_errors - self._report_bad
        self._report_ns, self._report_published = now_ns, published
        self._report_bad = stats.bad_frames + stats.sample_errors
        level = _LEVELS[state]
        if level == DiagnosticStatus.OK and new_bad:
            level = DiagnosticStatus.WARN
        status = DiagnosticStatus(
            level=level,
            name=f'{self.node.get_name()}: {self.name}',
            message=reason if not new_bad else f'{reason}; {new_bad} bad frame(s) skipped',
            hardware_id=self.port,
        )
        values = {
            'state': state.name,
            'port': self.port,
            'baudrate [bit/s]': self.baudrate,
            'published': published,
            'rate [Hz]': f'{rate:.1f}',
            'frames_ok': stats.frames_ok,
            'crc_errors': stats.crc_errors,
            'length_errors': stats.length_errors,
            'decode_errors': stats.decode_errors,
            'sample_errors': stats.sample_errors,
            'bytes_read': stats.bytes_read,
            'bytes_discarded': stats.bytes_discarded,
            'opens': stats.opens,
            'open_failures': stats.open_failures,
            'port_losses': stats.port_losses,
            'last_error': stats.last_error or '',
        }
        status.values = [KeyValue(key=k, value=str(v)) for k, v in values.items()]
        msg = DiagnosticArray()
        msg.header.stamp = now.to_msg()
        msg.status = [status]
        self._diagnostics.publish(msg)
