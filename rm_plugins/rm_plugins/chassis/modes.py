"""Chassis motion modes: the chassis-frame twist for RAW, FOLLOW, TWIST and GYRO.

Frames and signs (REP 103): x forward, y left, z up; yaw counter-clockwise positive seen
from above. The *gimbal frame* here is the chassis frame turned by the gimbal's yaw, i.e.
horizontal axes with x along the barrel's heading. The *yaw joint angle* phi is the
gimbal's heading relative to the chassis (the yaw motor's joint position, 0 when the
barrel points along chassis x, positive when the gimbal is turned left of the chassis):
``phi = yaw_gimbal - yaw_chassis``. With the chassis turning at wz and the gimbal at
``gimbal_yaw_rate`` (both in the world), ``dphi/dt = gimbal_yaw_rate - wz``.

One controller, :class:`ChassisModeController`, decides for every mode in one method:

- **RAW**: the command, a chassis-frame twist, passes through unchanged.
- **FOLLOW**: a PID (angle mode) turns the chassis until phi equals the follow offset;
  wz = PID + ``gimbal_yaw_rate`` (feed-forward: the chassis turns with the gimbal rather
  than lagging it). The translation, given in the gimbal frame, is rotated into the
  chassis frame, so "forward" is where the barrel points.
- **TWIST**: as FOLLOW, but the target swings: the chassis heading relative to the gimbal
  is ``amplitude * f(t)`` with f a sine or triangle wave of the configured period (phi
  target ``-amplitude * f(t)``); the wave's rate is fed forward too.
- **GYRO**: the chassis spins at a constant rate (optionally slower while translating
  fast, so the wheels keep headroom for the translation) and the gimbal-frame translation
  is rotated into the spinning chassis frame. The closed heading loop that keeps the
  spin what was asked (``GyroParams.heading``) runs after the spin's ramp
  (:mod:`rm_plugins.chassis.spin_heading`, used by the chassis plugin's planner).

Rotating the translation: the command is applied a little later (actuation latency) and
then held for a control period while phi keeps changing, so it is rotated by the angle
phi will have on average over that time::

    phi_used = phi + dphi/dt * (latency_s + dt / 2)

with dphi/dt the measured yaw joint rate if given, else ``gimbal_yaw_rate - wz``. This
matters in GYRO (at 10 rad/s and 25 ms an uncompensated path heads 0.25 rad off) and is
negligible in FOLLOW, where phi barely moves; the same rule applies to every gimbal-frame
mode. PASSIVE (motors limp) is not a motion mode: the plugin stops commanding instead.
"""

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

from rm_base.control.pid_form import PidConfig, build_pid
from rm_base.control.validation import require_non_negative, require_positive, require_real
from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry.kinematics import Twist2D, body_to_world_twist

from rm_plugins.chassis.spin_heading import OPEN_LOOP, SpinHeadingParams

_TAU = 2.0 * math.pi


class ChassisMotionMode(Enum):
    """How the chassis twist is made from a command; see the module docstring."""

    RAW = 'raw'
    FOLLOW = 'follow'
    TWIST = 'twist'
    GYRO = 'gyro'


class TwistWaveform(Enum):
    """Shape of the TWIST swing."""

    SINE = 'sine'
    TRIANGLE = 'triangle'


def twist_waveform(waveform: TwistWaveform, time_s: float, period_s: float) -> tuple[float, float]:
    """Return the swing f(t) in [-1, 1] and its rate df/dt [1/s].

    Both waves start at 0 rising: the sine is ``sin(2 pi t / T)``; the triangle rises
    linearly to 1 at T/4, falls to -1 at 3T/4 and returns to 0 at T (rate ±4/T).

    Args:
        waveform: Sine or triangle.
        time_s: Time since the swing started [s].
        period_s: Period T [s], > 0.
    """
    if waveform is TwistWaveform.SINE:
        angle = _TAU * time_s / period_s
        return math.sin(angle), _TAU / period_s * math.cos(angle)
    u = (time_s / period_s) % 1.0  # fraction of the period, in [0, 1)
    rate = 4.0 / period_s
    if u < 0.25:
        return 4.0 * u, rate
    if u < 0.75:
        return 2.0 - 4.0 * u, -rate
    return 4.0 * u - 4.0, rate


@dataclass(frozen=True, slots=True)
class FollowParams:
    """FOLLOW (and TWIST) heading control.

    Attributes:
        gains: PID (positional or incremental) from the heading error [rad] to wz
            [rad/s]; angle_mode must be on, so the chassis turns the short way round. Its
            output_limit bounds the feedback part of wz; the feed-forward comes on top.
        offset: Yaw joint angle phi the chassis holds in FOLLOW [rad]; 0 lines the chassis
            up with the gimbal, pi/4 keeps it turned 45° clockwise of the gimbal.
    """

    gains: PidConfig
    offset: float = 0.0

    def __post_init__(self) -> None:
        owner = type(self).__name__
        if not isinstance(self.gains, PidConfig):
            raise ConfigError(f'{owner}.gains must be a PID config, got {self.gains!r}')
        if not self.gains.angle_mode:
            raise ConfigError(f'{owner}.gains must have angle_mode=True (the error is an angle)')
        offset = require_real(owner, 'offset', self.offset)
        if not math.isfinite(offset):
            raise ConfigError(f'{owner}.offset must be finite, got {self.offset!r}')
        object.__setattr__(self, 'offset', offset)


@dataclass(frozen=True, slots=True)
class TwistParams:
    """TWIST swing.

    Attributes:
        amplitude: Largest chassis heading either side of the gimbal's [rad], in [0, pi).
        period_s: Duration of one full swing [s], > 0.
        waveform: Sine (smooth) or triangle (constant turn rate, harder to predict).
    """

    amplitude: float
    period_s: float
    waveform: TwistWaveform = TwistWaveform.SINE

    def __post_init__(self) -> None:
        owner = type(self).__name__
        amplitude = require_non_negative(owner, 'amplitude', self.amplitude)
        if amplitude >= math.pi:
            raise ConfigError(f'{owner}.amplitude must be < pi rad, got {self.amplitude!r}')
        object.__setattr__(self, 'amplitude', amplitude)
        object.__setattr__(self, 'period_s', require_positive(owner, 'period_s', self.period_s))
        if not isinstance(self.waveform, TwistWaveform):
            raise ConfigError(f'{owner}.waveform must be a TwistWaveform, got {self.waveform!r}')


@dataclass(frozen=True, slots=True)
class GyroParams:
    """GYRO spin.

    Attributes:
        spin_rate: Spin at standstill [rad/s]; the sign picks the direction (positive
            counter-clockwise).
        translating_spin_rate: |spin| once the commanded translation reaches
            translating_speed [rad/s], >= 0; linear in between. None: no reduction.
        translating_speed: Translation speed at which the spin has fallen to
            translating_spin_rate [m/s], > 0.
        heading: the closed heading loop while spinning (gain 0: open loop).
    """

    spin_rate: float
    translating_spin_rate: float | None = None
    translating_speed: float = 1.0
    heading: SpinHeadingParams = OPEN_LOOP

    def __post_init__(self) -> None:
        owner = type(self).__name__
        spin_rate = require_real(owner, 'spin_rate', self.spin_rate)
        if not math.isfinite(spin_rate):
            raise ConfigError(f'{owner}.spin_rate must be finite, got {self.spin_rate!r}')
        object.__setattr__(self, 'spin_rate', spin_rate)
        if self.translating_spin_rate is not None:
            object.__setattr__(
                self,
                'translating_spin_rate',
                require_non_negative(owner, 'translating_spin_rate', self.translating_spin_rate),
            )
        object.__setattr__(
            self,
            'translating_speed',
            require_positive(owner, 'translating_speed', self.translating_speed),
        )
        if not isinstance(self.heading, SpinHeadingParams):
            raise ConfigError(f'{owner}.heading must be a SpinHeadingParams, got {self.heading!r}')

    def spin_at(self, speed: float) -> float:
        """Return the spin rate wz [rad/s] while translating at speed [m/s] (>= 0)."""
        if self.translating_spin_rate is None:
            return self.spin_rate
        fraction = min(1.0, speed / self.translating_speed)
        magnitude = abs(self.spin_rate)
        magnitude += (self.translating_spin_rate - magnitude) * fraction
        return math.copysign(magnitude, self.spin_rate)


@dataclass(frozen=True, slots=True)
class ChassisModeParams:
    """Everything :class:`ChassisModeController` needs.

    Attributes:
        follow: FOLLOW heading control; TWIST uses the same PID.
        twist: TWIST swing.
        gyro: GYRO spin.
        latency_s: Time from this computation to the wheels acting on it [s], >= 0 (plugin
            to bridge, CAN, wheel speed loop); half the control period is added on top.
    """

    follow: FollowParams
    twist: TwistParams
    gyro: GyroParams
    latency_s: float = 0.0

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name, kind in (('follow', FollowParams), ('twist', TwistParams), ('gyro', GyroParams)):
            if not isinstance(getattr(self, name), kind):
                raise ConfigError(f'{owner}.{name} must be a {kind.__name__}')
        object.__setattr__(
            self, 'latency_s', require_non_negative(owner, 'latency_s', self.latency_s)
        )


class ChassisModeController:
    """Turns a command into a chassis-frame twist, for whichever motion mode is active.

    Changing mode (or :meth:`reset`) restarts the PID and the TWIST swing, so a mode never
    starts with another mode's integral.
    """

    __slots__ = ('_mode', '_params', '_pid', '_target_yaw_joint', '_twist_time_s')

    def __init__(self, params: ChassisModeParams) -> None:
        """Create a controller at rest.

        Raises:
            ConfigError: If params is not a ChassisModeParams.
        """
        if not isinstance(params, ChassisModeParams):
            raise ConfigError(f'params must be a ChassisModeParams, got {params!r}')
        self._params = params
        self._pid = build_pid(params.follow.gains)
        self.reset()

    @property
    def params(self) -> ChassisModeParams:
        """The parameters."""
        return self._params

    @property
    def mode(self) -> ChassisMotionMode | None:
        """Mode of the last update, None after construction or reset."""
        return self._mode

    @property
    def target_yaw_joint(self) -> float | None:
        """Yaw joint angle phi the last FOLLOW/TWIST update steered to [rad], else None."""
        return self._target_yaw_joint

    def set_params(self, params: ChassisModeParams) -> None:
        """New parameters (set while running); new gains restart the PID from rest.

        Raises:
            ConfigError: If params is not a ChassisModeParams.
        """
        if not isinstance(params, ChassisModeParams):
            raise ConfigError(f'params must be a ChassisModeParams, got {params!r}')
        if params.follow.gains != self._params.follow.gains:
            self._pid = build_pid(params.follow.gains)
        self._params = params

    def reset(self) -> None:
        """Forget the PID state, the swing phase and the mode (call on enable and disable)."""
        self._pid.reset()
        self._mode: ChassisMotionMode | None = None
        self._twist_time_s = 0.0
        self._target_yaw_joint: float | None = None

    def update(
        self,
        mode: ChassisMotionMode,
        command: Sequence[float],
        yaw_joint: float,
        dt: float,
        *,
        gimbal_yaw_rate: float = 0.0,
        yaw_joint_rate: float | None = None,
    ) -> Twist2D:
        """Compute the chassis-frame twist for one control period.

        Args:
            mode: The motion mode.
            command: (vx [m/s], vy [m/s], wz [rad/s]). RAW: a chassis-frame twist, used
                as is. Other modes: vx, vy in the gimbal frame; wz is ignored (the mode
                decides the turn).
            yaw_joint: Yaw joint angle phi, gimbal heading minus chassis heading [rad].
            dt: Time since the previous update [s], finite and > 0.
            gimbal_yaw_rate: The gimbal's yaw rate in the world [rad/s], fed forward in
                FOLLOW/TWIST (0 if unknown).
            yaw_joint_rate: Measured dphi/dt [rad/s] (the yaw motor's speed), used to
                rotate the translation; None estimates it as gimbal_yaw_rate - wz.

        Returns:
            The twist (vx, vy, wz) in the chassis frame [m/s, m/s, rad/s].

        Raises:
            InputRejectedError: If mode is not a ChassisMotionMode, dt is not finite and
                > 0, or a value is NaN or infinite. The state is left as it was.
        """
        if not isinstance(mode, ChassisMotionMode):
            raise InputRejectedError(f'unknown chassis motion mode {mode!r}')
        if not 0.0 < dt < math.inf:
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        try:
            vx, vy, wz = (float(value) for value in command)
        except (TypeError, ValueError) as err:
            raise InputRejectedError(f'command must be (vx, vy, wz), got {command!r}') from err
        values = (vx, vy, wz, yaw_joint, gimbal_yaw_rate)
        if not all(map(math.isfinite, values)) or (
            yaw_joint_rate is not None and not math.isfinite(yaw_joint_rate)
        ):
            raise InputRejectedError(
                'command, yaw_joint, gimbal_yaw_rate and yaw_joint_rate must be finite, got '
                f'{command!r}, {yaw_joint!r}, {gimbal_yaw_rate!r}, {yaw_joint_rate!r}'
            )

        entering = mode is not self._mode
        if entering:
            self._pid.reset()
            self._twist_time_s = 0.0
        self._mode = mode

        if mode is ChassisMotionMode.RAW:
            self._target_yaw_joint = None
            return Twist2D(vx, vy, wz)

        if mode is ChassisMotionMode.GYRO:
            self._target_yaw_joint = None
            wz = self._params.gyro.spin_at(math.hypot(vx, vy))
        else:
            if mode is ChassisMotionMode.FOLLOW:
                target, target_rate = self._params.follow.offset, 0.0
            else:
                twist = self._params.twist
                if not entering:
                    self._twist_time_s = (self._twist_time_s + dt) % twist.period_s
                swing, swing_rate = twist_waveform(
                    twist.waveform, self._twist_time_s, twist.period_s
                )
                # The chassis heading relative to the gimbal swings: that is -phi.
                target, target_rate = -twist.amplitude * swing, -twist.amplitude * swing_rate
            self._target_yaw_joint = target
            # The PID steers the chassis heading relative to the gimbal, -phi, which wz
            # raises: d(-phi)/dt = wz - gimbal_yaw_rate. So setpoint -target, measurement
            # -phi, and the rates the target and the gimbal move at are fed forward.
            wz = self._pid.update(-target, -yaw_joint, dt) + gimbal_yaw_rate - target_rate

        if yaw_joint_rate is None:
            yaw_joint_rate = gimbal_yaw_rate - wz
        heading = yaw_joint + yaw_joint_rate * (self._params.latency_s + 0.5 * dt)
        vx_chassis, vy_chassis, _ = body_to_world_twist((vx, vy, 0.0), heading)
        return Twist2D(vx_chassis, vy_chassis, wz)
