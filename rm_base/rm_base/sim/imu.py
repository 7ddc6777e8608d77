"""A simulated HiPNUC IMU that writes real 0x91 frames to a pseudo-terminal.

The IMU reads its orientation, angular velocity and specific force from the
:class:`~rm_base.sim.body.RobotBody` it is mounted on (chassis or gimbal) and sends them
at a fixed rate as HiPNUC 0x91 (IMUSOL) frames, encoded with
:mod:`rm_base.hardware.protocols.hipnuc`, on a simulated serial port
(:class:`~rm_base.sim.pty_port.PtyPort`) the driver opens as it opens ``/dev/ttyUSB0``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, TypedDict

import numpy as np

from rm_base.config.schema import Schema, integer, number, numbers, string
from rm_base.geometry import (
    rotation_matrix_from_rpy,
)
from rm_base.hardware.protocols import hipnuc
from rm_base.sim.body import Mount, RobotBody
from rm_base.sim.pty_port import PtyPort
from rm_base.sim_devices.errors import SimConfigError
from rm_base.sim_devices.schedule import RateSchedule

_NS_PER_S = 1_000_000_000
_NS_PER_MS = 1_000_000
#: A UART byte is 10 bits on the wire (start, 8 data, stop).
_BITS_PER_BYTE = 10
_FRAME_BYTES = hipnuc.HEADER_LENGTH + 76


Vector3 = tuple[float, float, float]


class ImuSample(TypedDict):
    """What the simulated sensor measures at one instant (see ``SimImu.sample``)."""

    acc: Vector3
    gyr: Vector3
    mag: Vector3
    quat: tuple[float, float, float, float]
    euler: Vector3


class SimImu:
    """A HiPNUC IMU fixed to the chassis or the gimbal, on a pseudo-terminal.

    Attributes:
        name: name in the world.
        path: the configured path (symlink to the terminal), expanded.
        device_path: the pseudo-terminal's slave device (``/dev/pts/N``).
        mount: the body it is fixed to.
        rate_hz: frames per second.
        frames_written: frames written to the terminal.
        frames_dropped: frames dropped because nobody read the terminal.
    """

    def __init__(
        self,
        body: RobotBody,
        *,
        name: str = 'imu',
        path: str,
        mount: Mount = Mount.GIMBAL,
        rate_hz: float = 100.0,
        baudrate: int = 115200,
        mount_rpy: Sequence[float] = (0.0, 0.0, 0.0),
        temperature: int = 25,
        pressure: float = 101325.0,
        magnetic_field: Sequence[float] = (0.0, 0.0, 0.0),
    ):
        """Open the pseudo-terminal and create the symlink.

        Args:
            body: the robot body the IMU reads its motion from.
            name: name in the world.
            path: where to put the symlink; ``~`` and ``${VAR}`` are expanded, missing
                directories are created, a stale symlink is replaced.
            mount: chassis or gimbal.
            rate_hz: frame rate [Hz].
            baudrate: the real link's baud rate [bit/s]; only checks that ``rate_hz``
                frames fit on it (82 bytes each).
            mount_rpy: sensor orientation on its body (roll, pitch, yaw) [rad].
            temperature: reported temperature [°C].
            pressure: reported air pressure [Pa].
            magnetic_field: world magnetic field (x, y, z) [µT], rotated into the sensor.

        Raises:
            SimConfigError: bad parameters, or the path exists and is not a symlink.
        """
        if not (math.isfinite(rate_hz) and rate_hz > 0.0):
            raise SimConfigError(f'{name}: rate_hz must be > 0, got {rate_hz}')
        needed = rate_hz * _FRAME_BYTES * _BITS_PER_BYTE
        if needed > baudrate:
            raise SimConfigError(
                f'{name}: {rate_hz} Hz of {_FRAME_BYTES}-byte frames needs {needed:.0f} bit/s, '
                f'more than {baudrate} baud'
            )
        if len(mount_rpy) != 3 or len(magnetic_field) != 3:
            raise SimConfigError(f'{name}: mount_rpy and magnetic_field need 3 values each')
        self.name = name
        self.body = body
        self.mount = mount
        self.rate_hz = float(rate_hz)
        self.temperature = int(temperature)
        self.pressure = float(pressure)
        self.magnetic_field = np.array(magnetic_field, dtype=float)
        self.mount_rotation = rotation_matrix_from_rpy(*(float(v) for v in mount_rpy))
        # float copies for sample()
        self._magnetic_field = tuple(self.magnetic_field.tolist())
        self._mount = _rows(self.mount_rotation.tolist())
        self._schedule = RateSchedule(rate_hz, first_ns=round(_NS_PER_S / rate_hz))
        self.port = PtyPort(path, name)

    # -- measurement -----------------------------------------------------------------------

    def sensor_rotation(self) -> np.ndarray:
        """Rotation matrix world <- sensor."""
        return self.body.orientation(self.mount) @ self.mount_rotation

    def sample(self) -> ImuSample:
        """What the sensor measures now, in the sensor frame (SI).

        Plain floats: at 400 Hz under the world lock the numpy path (``sensor_rotation``
        and the validating ``rm_base.geometry`` conversions) cost ~130 µs a frame,
        this ~20 µs (bench/). ``sensor_rotation()`` stays the reference the tests use.

        Returns:
            ``acc`` specific force [m/s²] (reads +g up at rest), ``gyr`` [rad/s],
            ``mag`` [µT], ``quat`` (w, x, y, z) world <- sensor, ``euler`` (roll, pitch,
            yaw) [rad] of that rotation (R = Rz(yaw) Ry(pitch) Rx(roll)).
        """
        body = self.body
        r = _matmul(_matrix_from_rpy(*body.attitude(self.mount)), self._mount)
        ax, ay, az = body.world_acceleration().tolist()
        x, y, z, w = _quaternion_from_matrix(r)
        return {
            'acc': _transpose_times(r, ax, ay, az + hipnuc.STANDARD_GRAVITY),
            'gyr': _transpose_times(r, *body.angular_velocity(self.mount).tolist()),
            'mag': _transpose_times(r, *self._magnetic_field),
            'quat': (w, x, y, z),
            'euler': (
                math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)),
                math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x)))),
                math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)),
            ),
        }

    def frame(self, now_ns: int, device_ns: int | None = None) -> bytes:
        """One complete 0x91 frame for the current motion.

        Args:
            now_ns: simulation time [ns].
            device_ns: the device's own clock for ``system_time_ms`` [ns]; default
                now_ns. A real IMU's counter runs on with real time whatever happens to
                the simulation's clock (which slips when the machine is starved).
        """
        device_ns = now_ns if device_ns is None else device_ns
        s = self.sample()
        payload = hipnuc.encode_imusol(
            acc=s['acc'],
            gyr=s['gyr'],
            mag=s['mag'],
            euler=s['euler'],
            quat=s['quat'],
            temperature=self.temperature,
            pressure=self.pressure,
            system_time_ms=(device_ns // _NS_PER_MS) & 0xFFFFFFFF,
        )
        return hipnuc.encode_frame(payload)

    # -- output ----------------------------------------------------------------------------

    def poll(self, now_ns: int, device_ns: int | None = None) -> bytes | None:
        """The frame due at ``now_ns``, or None; the caller writes it (:meth:`write`).

        device_ns: the device clock (see :meth:`frame`).
        """
        if self.port.closed or not self._schedule.due(now_ns):
            return None
        return self.frame(now_ns, device_ns)

    def tick(self, now_ns: int) -> bool:
        """Write a frame if one is due at ``now_ns``; return whether one was due."""
        frame = self.poll(now_ns)
        if frame is None:
            return False
        self.write(frame)
        return True

    def write(self, data: bytes) -> None:
        """Write a frame to the terminal (see :meth:`PtyPort.write`)."""
        self.port.write(data)

    def close(self) -> None:
        """Close the terminal and remove the symlink (idempotent)."""
        self.port.close()

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self.port.closed

    @property
    def path(self) -> str:
        """The configured path (symlink to the terminal), expanded."""
        return self.port.path

    @property
    def device_path(self) -> str:
        """The pseudo-terminal's slave device (``/dev/pts/N``)."""
        return self.port.device_path

    @property
    def frames_written(self) -> int:
        """Frames written to the terminal."""
        return self.port.frames_written

    @property
    def frames_dropped(self) -> int:
        """Frames dropped because nobody read the terminal."""
        return self.port.frames_dropped

    def __enter__(self) -> SimImu:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


Matrix = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]


def _rows(m: list[list[float]]) -> Matrix:
    return (tuple(m[0]), tuple(m[1]), tuple(m[2]))  # type: ignore[return-value]


def _matrix_from_rpy(roll: float, pitch: float, yaw: float) -> Matrix:
    """Rz(yaw) @ Ry(pitch) @ Rx(roll), as ``rm_base.geometry.rotation_matrix_from_rpy``."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def _matmul(a: Matrix, b: Matrix) -> Matrix:
    return _rows([[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)])


def _transpose_times(r: Matrix, x: float, y: float, z: float) -> tuple[float, float, float]:
    """``r.T @ (x, y, z)``: a world vector in the frame whose axes are r's columns."""
    return (
        r[0][0] * x + r[1][0] * y + r[2][0] * z,
        r[0][1] * x + r[1][1] * y + r[2][1] * z,
        r[0][2] * x + r[1][2] * y + r[2][2] * z,
    )


def _quaternion_from_matrix(r: Matrix) -> tuple[float, float, float, float]:
    """(x, y, z, w), w >= 0, of a rotation matrix built here (Shepperd, no validation).

    Same method as ``rm_base.geometry.quaternion_from_rotation_matrix``, which also
    checks that the matrix is a rotation (numpy, the bulk of its cost).
    """
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = r
    trace = m00 + m11 + m22
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        x, y, z, w = (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s
    elif m00 > m11 and m00 > m22:
        s = 2.0 * math.sqrt(1.0 + m00 - m11 - m22)
        x, y, z, w = 0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s
    elif m11 > m22:
        s = 2.0 * math.sqrt(1.0 + m11 - m00 - m22)
        x, y, z, w = (m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s
    else:
        s = 2.0 * math.sqrt(1.0 + m22 - m00 - m11)
        x, y, z, w = (m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s
    if w < 0.0:
        x, y, z, w = -x, -y, -z, -w
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    return x / norm, y / norm, z / norm, w / norm


#: ``sim.imu``: one simulated HiPNUC IMU on a pty.
IMU_SCHEMA = Schema((
    string('path', nonempty=True,
           description="the pty's link, e.g. /tmp/rm_sim_${ROS_DOMAIN_ID}/imu "
           '(${VAR} expanded)'),
    string('name', 'imu', description='name in logs'),
    string('mount', 'gimbal', choices=('gimbal', 'chassis'),
           description='the body the IMU sits on'),
    number('rate_hz', 100.0, unit='Hz', gt=0.0, description='frames per second'),
    integer('baudrate', 115200, ge=1, description="the port's baud rate"),
    numbers('mount_rpy', (0.0, 0.0, 0.0), unit='rad', length=3,
            description='roll, pitch, yaw of the IMU on its body'),
    integer('temperature', 25, unit='degC', description='temperature it reports'),
    number('pressure', 101325.0, unit='Pa', description='air pressure it reports'),
    numbers('magnetic_field', (0.0, 0.0, 0.0), unit='uT', length=3,
            description='magnetic field it reports (body frame)'),
))


def imu_from_config(config: Mapping[str, Any], body: RobotBody) -> SimImu:
    """Build an IMU from a plain dict (keys: ``IMU_SCHEMA``).

    Raises:
        SimConfigError: a missing, unknown or invalid key.
    """
    values = IMU_SCHEMA.read('imu', config, SimConfigError)
    return SimImu(body, **{**values, 'mount': Mount(values['mount'])})
