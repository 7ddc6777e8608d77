"""StandChassis parameters: read once at init from the robot config, checked, frozen.

Why one module: it declares every key of the chassis, wheel layouts (mecanum, omni,
swerve) included, so one file is the whole of what a robot config may say to it.

Every key is under the plugin's prefix (``chassis.``). Required geometry has no default,
so a config that omits it fails at start-up with one line naming the key and its unit.
See ``rm_bringup/config/standard.yaml`` for a complete, commented example.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, make_dataclass
from enum import Enum
from typing import Any

from rm_base.config.schema import declare, group, number
from rm_base.control import ChassisPowerModel, PidGains, RampLimits
from rm_base.control.pid_form import IncrementalPidConfig, PidConfig, incremental_like
from rm_base.geometry import (
    MECANUM_ROLLER_SIGNS,
    SwerveKinematics,
    WheelKinematics,
    mecanum_wheels,
    omni_wheels,
    square_modules,
)
from rm_base.plugin import ParameterError, PluginParams
from rm_base.plugin.pid_params import loop_pid

from rm_plugins.chassis.buffer_energy import BufferEnergyParams
from rm_plugins.chassis.commands import SpeedGear
from rm_plugins.chassis.modes import (
    ChassisModeParams,
    FollowParams,
    GyroParams,
    TwistParams,
    TwistWaveform,
)
from rm_plugins.chassis.position import DEFAULT_POSITION, PositionConfig
from rm_plugins.chassis.spin_heading import SpinHeadingParams

# SRML's speed gears: (linear, angular) coefficients on /vel_cmd by default.
_GEAR_DEFAULTS = {
    SpeedGear.SLOW: (0.5, 0.5),
    SpeedGear.NORMAL: (1.0, 1.0),
    SpeedGear.FAST: (1.5, 1.0),
}


class Kinematics(Enum):
    """Wheel layout."""

    MECANUM = 'mecanum'  # four wheels FL, FR, RL, RR on a rectangle
    OMNI = 'omni'  # N omni wheels on a circle, rolling tangentially
    SWERVE = 'swerve'  # four steered wheels FL, FR, RL, RR on a rectangle


class ImuMount(Enum):
    """The body the IMU on the imu topic is fixed to."""

    GIMBAL = 'gimbal'  # chassis yaw = IMU yaw - yaw joint angle
    CHASSIS = 'chassis'  # chassis yaw = IMU yaw
    NONE = 'none'  # no IMU: the odometry yaw comes from the wheels


@dataclass(frozen=True)
class ChassisConfig:
    """Everything StandChassis reads from its parameters (SI units).

    Attributes:
        kinematics: wheel layout.
        wheel_joints: joint names, in the kinematics' wheel order.
        wheels: the wheel kinematics (Jacobian) built from the geometry, or a swerve
            chassis' modules.
        steer_joints: a swerve chassis' steering joints, in the wheel order (angle 0: the
            module rolls along base x); empty for fixed wheels.
        max_wheel_speed: largest |wheel speed| target [rad/s].
        wheel_feedback_timeout: wheel feedback older than this is missing [s].
        vel_cmd_timeout: a /vel_cmd older than this is no velocity (brake to zero) [s].
        yaw_joint: the gimbal yaw joint whose angle is the gimbal's heading on the chassis.
        yaw_zero: joint position at which the gimbal points along chassis x [rad].
        modes: FOLLOW/TWIST/GYRO parameters.
        linear_limits: default ramp of vx and vy.
        angular_limits: default ramp of wz.
        power_model: power model of the chassis.
        power_limit: default chassis power limit [W]; with the referee, the limit while it is
            silent.
        referee_power: take the limit from /referee/robot_status and spend the buffer energy
            of /referee/power_heat this way; None: the configured or commanded limit.
        referee_timeout: no /referee/robot_status this long: the default limit [s].
        imu_mount: where the IMU on imu_topic is fixed.
        imu_topic: sensor_msgs/Imu topic.
        imu_timeout: an IMU sample older than this is not used [s].
        imu_reference_timeout: after the IMU has been unusable this long, its next sample
            fixes a new heading reference (the yaw stays continuous) [s].
        odom_frame: frame of the odometry pose.
        base_frame: child frame (the robot).
        publish_tf: send odom -> base_frame on /tf and into the frame tree.
        publish_rate: rate of /chassis_state and /odom [Hz].
        gears: per speed gear, the (linear, angular) coefficients on /vel_cmd.
        position: how POSITION moves.
    """

    kinematics: Kinematics
    wheel_joints: tuple[str, ...]
    wheels: WheelKinematics | SwerveKinematics
    max_wheel_speed: float
    wheel_feedback_timeout: float
    vel_cmd_timeout: float
    yaw_joint: str
    yaw_zero: float
    modes: ChassisModeParams
    linear_limits: RampLimits
    angular_limits: RampLimits
    power_model: ChassisPowerModel
    power_limit: float
    imu_mount: ImuMount
    imu_topic: str
    imu_timeout: float
    imu_reference_timeout: float
    odom_frame: str
    base_frame: str
    publish_tf: bool
    publish_rate: float
    referee_power: BufferEnergyParams | None = None
    referee_timeout: float = 1.0
    gears: dict[SpeedGear, tuple[float, float]] = dataclasses.field(
        default_factory=lambda: dict.fromkeys(SpeedGear, (1.0, 1.0))
    )
    position: PositionConfig = DEFAULT_POSITION
    steer_joints: tuple[str, ...] = ()



def _wheels(
    p: PluginParams, kind: Kinematics, joints: tuple[str, ...]
) -> WheelKinematics | SwerveKinematics:
    radius = p.double('wheel_radius', description='wheel radius', unit='m', gt=0.0)
    if kind in (Kinematics.MECANUM, Kinematics.SWERVE):
        _four(p, 'wheel_joints', joints, kind, 'wheels')
        wheelbase = p.double(
            'wheelbase', description='distance between front and rear axles', unit='m', gt=0.0
        )
        track = p.double(
            'track', description='distance between left and right wheel centres', unit='m',
            gt=0.0,
        )
        if kind is Kinematics.SWERVE:
            return SwerveKinematics(square_modules(wheelbase, track, radius))
        signs = p.integer_array(
            'roller_signs', list(MECANUM_ROLLER_SIGNS),
            description='sign of each roller angle, FL, FR, RL, RR (X layout: -1, 1, 1, -1)',
            length=4, ge=-1, le=1,
        )
        if 0 in signs:
            raise ParameterError(
                f'{_where(p)}: parameter {p.key("roller_signs")!r} entries must be 1 or -1, '
                f'got {list(signs)}',
                plugin=p.plugin, key=p.key('roller_signs'),
            )
        wheels = mecanum_wheels(wheelbase, track, radius, signs)
    else:
        angles = p.double_array(
            'mounting_angles',
            description='angle of each wheel position from base x, in wheel_joints order',
            unit='rad',
        )
        if len(angles) != len(joints):
            raise ParameterError(
                f'{_where(p)}: parameter {p.key("mounting_angles")!r} has {len(angles)} '
                f'entries but wheel_joints names {len(joints)} wheels',
                plugin=p.plugin, key=p.key('mounting_angles'),
            )
        distance = p.double(
            'centre_distance', description='distance from the base origin to each wheel centre',
            unit='m', gt=0.0,
        )
        wheels = omni_wheels(angles, distance, radius)
    return WheelKinematics(wheels)


def _four(
    p: PluginParams, key: str, joints: tuple[str, ...], kind: Kinematics, what: str
) -> None:
    if len(joints) != 4:
        raise ParameterError(
            f'{_where(p)}: parameter {p.key(key)!r} must name 4 {what} in the order FL, FR, '
            f'RL, RR for {kind.value}, got {len(joints)}',
            plugin=p.plugin, key=p.key(key),
        )


def _steer_joints(p: PluginParams, kind: Kinematics, wheels: tuple[str, ...]) -> tuple[str, ...]:
    if kind is not Kinematics.SWERVE:
        return ()
    joints = p.string_array(
        'steer_joints',
        description='swerve: steering joint names, FL, FR, RL, RR (angle 0: the module '
        'rolls along base x)',
        unique=True,
    )
    _four(p, 'steer_joints', joints, kind, 'steering joints')
    shared = sorted(set(joints) & set(wheels))
    if shared:
        raise ParameterError(
            f'{_where(p)}: joint(s) {", ".join(shared)} both steer and drive',
            plugin=p.plugin, key=p.key('steer_joints'),
        )
    return joints


def _ramp_tuning(axis: str, unit: str, defaults: tuple[float, ...]) -> type:
    """One axis' live acceleration limits (``ramp.<axis>.*``)."""
    launch, normal, brake, launch_speed = defaults
    return make_dataclass(f'{axis.title()}Ramp', [
        ('launch_acceleration', float, declare(
            number, launch, tunable=True, unit=f'{unit}/s', gt=0.0,
            description=f'{axis} acceleration limit from standstill (below launch_speed)')),
        ('normal_acceleration', float, declare(
            number, normal, tunable=True, unit=f'{unit}/s', gt=0.0,
            description=f'{axis} acceleration limit when already moving')),
        ('brake_acceleration', float, declare(
            number, brake, tunable=True, unit=f'{unit}/s', gt=0.0,
            description=f'{axis} deceleration limit (slowing down, reversing, no /vel_cmd)')),
        ('launch_speed', float, declare(
            number, launch_speed, tunable=True, unit=unit, ge=0.0,
            description=f'{axis} speed below which the launch limit applies')),
    ], frozen=True, kw_only=True)


@dataclass(frozen=True, kw_only=True)
class RampTuning:
    """The acceleration limits of /vel_cmd (``ramp.*``)."""

    linear: Any = group(_ramp_tuning('linear', 'm/s', (4.0, 6.0, 8.0, 0.3)))
    angular: Any = group(_ramp_tuning('angular', 'rad/s', (20.0, 30.0, 40.0, 1.0)))


def _ramp_limits(axis: Any) -> RampLimits:
    return RampLimits(
        launch_acceleration=axis.launch_acceleration,
        normal_acceleration=axis.normal_acceleration,
        brake_acceleration=axis.brake_acceleration, launch_speed=axis.launch_speed,
    )


def _live(default: float, unit: str, description: str, **bounds: float) -> Any:
    return declare(number, default, tunable=True, unit=unit, description=description,
                   **bounds)


@dataclass(frozen=True, kw_only=True)
class FollowPidTuning:
    """FOLLOW's (and TWIST's) heading PID, heading error [rad] -> wz [rad/s]."""

    kp: float = _live(10.0, 'rad/s/(rad)', 'follow.pid proportional gain', ge=0.0)
    ki: float = _live(0.0, 'rad/s/(rad*s)', 'follow.pid integral gain', ge=0.0)
    kd: float = _live(0.0, 'rad/s/(rad/s)', 'follow.pid derivative gain', ge=0.0)
    output_limit: float = _live(8.0, 'rad/s', 'follow.pid output limit', gt=0.0)
    integral_limit: float = _live(1.0, 'rad/s', 'follow.pid integral term limit', ge=0.0)
    integral_separation: float = _live(
        0.3, 'rad', 'follow.pid: integrate only while |error| is below this', gt=0.0)


@dataclass(frozen=True, kw_only=True)
class FollowTuning:
    """The live part of ``follow.*``."""

    pid: FollowPidTuning = group(FollowPidTuning)


@dataclass(frozen=True, kw_only=True)
class TwistTuning:
    """TWIST's swing (``twist.*``; the waveform is read at start-up)."""

    amplitude: float = _live(0.6, 'rad', 'TWIST swing either side of the gimbal heading',
                             ge=0.0, lt=math.pi)
    period: float = _live(1.2, 's', 'TWIST period of one full swing', gt=0.0)


@dataclass(frozen=True, kw_only=True)
class HeadingTuning:
    """GYRO's heading loop (``gyro.heading.*``)."""

    gain: float = _live(5.0, '1/s', 'GYRO heading loop: spin-rate correction per rad the '
                        'odometry heading strays from the spin asked for; 0: open loop', ge=0.0)
    max_error: float = _live(0.5, 'rad', 'GYRO heading loop: largest heading error it acts '
                             'on (the correction is at most gain * max_error)', gt=0.0)


@dataclass(frozen=True, kw_only=True)
class GyroTuning:
    """GYRO's spin (``gyro.*``; the translating reduction is read at start-up)."""

    spin_rate: float = _live(6.0, 'rad/s',
                             'GYRO spin rate at standstill (> 0 counter-clockwise)')
    heading: HeadingTuning = group(HeadingTuning)


def _follow_gains(tuning: FollowPidTuning) -> PidGains:
    return PidGains(
        kp=tuning.kp, ki=tuning.ki, kd=tuning.kd, output_limit=tuning.output_limit,
        integral_limit=tuning.integral_limit, integral_separation=tuning.integral_separation,
        angle_mode=True,
    )


def _gear_tuning(gear: SpeedGear) -> type:
    """One speed gear's live factors (``gears.<gear>.*``), with SRML's defaults."""
    name = gear.name.lower()
    linear, angular = _GEAR_DEFAULTS[gear]
    return make_dataclass(f'{gear.name.title()}Gear', [
        ('linear', float, declare(
            number, linear, tunable=True, unit='1', gt=0.0,
            description=f'{name} gear (ChassisCmd.speed_gear): factor on /vel_cmd vx, vy (the '
            'wheel speed limit still applies)')),
        ('angular', float, declare(
            number, angular, tunable=True, unit='1', gt=0.0,
            description=f"{name} gear: factor on /vel_cmd wz (RAW's rotation)")),
    ], frozen=True, kw_only=True)


@dataclass(frozen=True, kw_only=True)
class GearTuning:
    """The speed gears' factors on /vel_cmd (``gears.*``)."""

    slow: Any = group(_gear_tuning(SpeedGear.SLOW))
    normal: Any = group(_gear_tuning(SpeedGear.NORMAL))
    fast: Any = group(_gear_tuning(SpeedGear.FAST))


@dataclass(frozen=True, kw_only=True)
class PowerTuning:
    """The live part of ``power.*``: the default limit and the wheels' power model."""

    default_limit: float = declare(
        number, 60.0, tunable=True, unit='W', gt=0.0,
        description='chassis power limit when /chassis_cmd gives none (with from_referee: '
        'while the referee is silent)',
    )
    k1: float = declare(number, 2.96, tunable=True, unit='W/(N*m)^2', ge=0.0,
                        description='copper-loss coefficient per wheel motor')
    k2: float = declare(number, 3.08e-3, tunable=True, unit='W/(rad/s)^2', ge=0.0,
                        description='speed-loss coefficient per wheel motor')
    static_power: float = declare(number, 2.8, tunable=True, unit='W', ge=0.0,
                                  description='chassis rail power at rest')


@dataclass(frozen=True, kw_only=True)
class ChassisTuning:
    """What may change while the chassis runs: gears, ramps, power, the modes' loops."""

    gears: GearTuning = group(GearTuning)
    ramp: RampTuning = group(RampTuning)
    power: PowerTuning = group(PowerTuning)
    follow: FollowTuning = group(FollowTuning)
    twist: TwistTuning = group(TwistTuning)
    gyro: GyroTuning = group(GyroTuning)


def _gears(tuning: ChassisTuning) -> dict[SpeedGear, tuple[float, float]]:
    return {gear: (factors.linear, factors.angular) for gear, factors in (
        (SpeedGear.SLOW, tuning.gears.slow), (SpeedGear.NORMAL, tuning.gears.normal),
        (SpeedGear.FAST, tuning.gears.fast))}


def _power_model(tuning: ChassisTuning) -> ChassisPowerModel:
    power = tuning.power
    return ChassisPowerModel(k1=power.k1, k2=power.k2, static_power_w=power.static_power)


def _modes(modes: ChassisModeParams, tuning: ChassisTuning) -> ChassisModeParams:
    """The mode parameters with the live values of tuning (the form of the PID kept)."""
    positional = _follow_gains(tuning.follow.pid)
    gains: PidConfig = positional
    if isinstance(modes.follow.gains, IncrementalPidConfig):
        gains = incremental_like(positional, modes.follow.gains.setpoint_td)
    gyro = tuning.gyro
    return dataclasses.replace(
        modes,
        follow=dataclasses.replace(modes.follow, gains=gains),
        twist=dataclasses.replace(modes.twist, amplitude=tuning.twist.amplitude,
                                  period_s=tuning.twist.period),
        gyro=dataclasses.replace(modes.gyro, spin_rate=gyro.spin_rate, heading=SpinHeadingParams(
            gyro.heading.gain, gyro.heading.max_error)),
    )


def with_tuning(config: ChassisConfig, tuning: ChassisTuning) -> ChassisConfig:
    """The config with the live values of tuning (set while running)."""
    return dataclasses.replace(
        config, gears=_gears(tuning), power_limit=tuning.power.default_limit,
        modes=_modes(config.modes, tuning),
        linear_limits=_ramp_limits(tuning.ramp.linear),
        angular_limits=_ramp_limits(tuning.ramp.angular), power_model=_power_model(tuning),
    )


def _where(p: PluginParams) -> str:
    kind = f' ({p.plugin_type})' if p.plugin_type else ''
    return f"plugin '{p.plugin}'{kind}"


def read_config(p: PluginParams, tuning: ChassisTuning) -> ChassisConfig:
    """Declare and read every start-up StandChassis parameter; the live ones come in tuning.

    Raises:
        ParameterError: a parameter is missing, of the wrong type or out of range; the
            message names the plugin, the key and the expected unit.
        PluginConfigError: the values do not fit together (e.g. the wheel count).
    """
    kind = p.choice(
        'kinematics', Kinematics, description='wheel layout: mecanum, omni or swerve'
    )
    joints = p.string_array(
        'wheel_joints',
        description='wheel joint names; mecanum, swerve: FL, FR, RL, RR; omni: as '
        'mounting_angles',
        unique=True,
    )
    wheels = _wheels(p, kind, joints)
    steer_joints = _steer_joints(p, kind, joints)
    max_wheel_speed = p.double(
        'max_wheel_speed', description='largest wheel speed target', unit='rad/s', gt=0.0
    )
    follow = FollowParams(
        loop_pid(p, 'follow.pid', _follow_gains(tuning.follow.pid), setpoint_unit='rad'),
        p.double('follow.offset', 0.0,
                 description='yaw joint angle held in FOLLOW (gimbal left of chassis > 0)',
                 unit='rad', ge=-math.pi, le=math.pi),
    )
    twist = TwistParams(
        tuning.twist.amplitude, tuning.twist.period,
        p.choice('twist.waveform', TwistWaveform, TwistWaveform.SINE,
                 description='TWIST wave: sine or triangle'),
    )
    spin = tuning.gyro.spin_rate
    gyro = GyroParams(
        spin,
        p.double('gyro.translating_spin_rate', abs(spin),
                 description='GYRO |spin rate| once translating at gyro.translating_speed '
                 '(default: |spin_rate| at start-up)', unit='rad/s', ge=0.0),
        p.double('gyro.translating_speed', 1.0,
                 description='translation speed at which GYRO spins at translating_spin_rate',
                 unit='m/s', gt=0.0),
        SpinHeadingParams(tuning.gyro.heading.gain, tuning.gyro.heading.max_error),
    )
    modes = ChassisModeParams(
        follow, twist, gyro,
        latency_s=p.double('latency', 0.0,
                           description='command-to-wheel latency the gimbal-frame rotation '
                           'looks ahead by', unit='s', ge=0.0, le=0.5),
    )
    return ChassisConfig(
        kinematics=kind,
        wheel_joints=joints,
        wheels=wheels,
        steer_joints=steer_joints,
        max_wheel_speed=max_wheel_speed,
        wheel_feedback_timeout=p.double(
            'wheel_feedback_timeout', 0.1,
            description='wheel feedback older than this counts as missing', unit='s', gt=0.0),
        vel_cmd_timeout=p.double(
            'vel_cmd_timeout', 0.25,
            description='/vel_cmd older than this: translation brakes to zero', unit='s',
            gt=0.0),
        yaw_joint=p.string('yaw_joint', 'yaw',
                           description='gimbal yaw joint (its angle is the gimbal heading '
                           'relative to the chassis)'),
        yaw_zero=p.double('yaw_zero', 0.0,
                          description='yaw joint position with the gimbal along chassis x',
                          unit='rad'),
        modes=modes,
        linear_limits=_ramp_limits(tuning.ramp.linear),
        angular_limits=_ramp_limits(tuning.ramp.angular),
        power_model=_power_model(tuning),
        power_limit=tuning.power.default_limit,
        **_referee_power(p),
        imu_mount=p.choice('imu.mount', ImuMount, ImuMount.GIMBAL,
                           description='body the IMU is fixed to: gimbal, chassis or none'),
        imu_topic=p.string('imu.topic', 'imu', description='sensor_msgs/Imu topic'),
        imu_timeout=p.double('imu.timeout', 0.1,
                             description='IMU samples older than this are not used', unit='s',
                             gt=0.0),
        imu_reference_timeout=p.double(
            'imu.reference_timeout', 1.0,
            description='after the IMU has been unusable this long its next sample is a new '
            'heading reference; shorter gaps keep the reference (the yaw returns to the '
            "IMU's)", unit='s', gt=0.0),
        odom_frame=p.string('odom.frame_id', 'odom', description='odometry frame'),
        base_frame=p.string('odom.child_frame_id', 'base_link', description='robot frame'),
        publish_tf=p.boolean('odom.publish_tf', True,
                             description='broadcast odom -> base_link on /tf'),
        publish_rate=p.double('publish_rate', 100.0,
                              description='rate of /chassis_state and /odom', unit='Hz',
                              gt=0.0),
        gears=_gears(tuning),
        position=_position(p),
    )


def _position(p: PluginParams) -> PositionConfig:
    """POSITION mode (``position.*``)."""
    g = p.group('position')
    return PositionConfig(
        max_speed=g.double('max_speed', DEFAULT_POSITION.max_speed, unit='m/s', gt=0.0,
                           description='top translation speed of a POSITION move'),
        max_rate=g.double('max_rate', DEFAULT_POSITION.max_rate, unit='rad/s', gt=0.0,
                          description='top turn rate of a POSITION move'),
        gain=g.double('gain', DEFAULT_POSITION.gain, unit='1/s', gt=0.0,
                      description='speed per unit of remaining offset near the goal'),
        tolerance=g.double('tolerance', DEFAULT_POSITION.tolerance, unit='m', gt=0.0,
                           description='a POSITION move has arrived within this distance'),
        yaw_tolerance=g.double('yaw_tolerance', DEFAULT_POSITION.yaw_tolerance, unit='rad', gt=0.0,
                               description='and within this heading error'),
    )


def _referee_power(p: PluginParams) -> dict[str, Any]:
    """The power limit from the referee (``power.*``), declared whether it is on or not."""
    on = p.boolean(
        'power.from_referee', False,
        description='take the limit from /referee/robot_status and spend the buffer energy of '
        '/referee/power_heat (the referee plugin)',
    )
    params = BufferEnergyParams(
        reserve_j=p.double('power.buffer_reserve', 20.0, unit='J', ge=0.0,
                           description='buffer energy kept; spent above it, refilled below'),
        gain_w_per_j=p.double('power.buffer_gain', 2.0, unit='W/J', ge=0.0,
                              description='extra power per joule above the reserve'),
        max_boost_w=p.double('power.max_boost', 60.0, unit='W', ge=0.0,
                             description='most power above the referee limit'),
    )
    timeout = p.double('power.referee_timeout', 1.0, unit='s', gt=0.0,
                       description='no /referee/robot_status this long -> default_limit')
    return {'referee_power': params if on else None, 'referee_timeout': timeout}
