"""StandGimbal configuration: the live tuning (declared once) and the start-up config."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, make_dataclass
from typing import Any

from rm_base.config.schema import declare, group, number
from rm_base.control import IncrementalPidConfig, PidConfig, PidGains
from rm_base.control.pid_form import incremental_like
from rm_base.geometry.ballistics import STANDARD_GRAVITY, ProjectileModel
from rm_base.plugin import PluginConfigError, PluginParams
from rm_base.plugin.pid_params import loop_pid

from rm_plugins.gimbal.frames import FramesConfig, read_frames


@dataclass(frozen=True)
class AxisConfig:
    """One gimbal axis (yaw or pitch).

    Attributes:
        joint: joint name in the robot config.
        angle_pid: outer loop: world angle error [rad] -> world rate [rad/s]; angle mode,
            positional or incremental (``<axis>_pid.form``); its output_limit is the axis'
            largest world rate.
        max_joint_velocity: largest joint velocity target sent to the bridge [rad/s].
    """

    joint: str
    angle_pid: PidConfig
    max_joint_velocity: float


@dataclass(frozen=True)
class GimbalConfig:
    """Everything StandGimbal reads at start-up (SI, REP 103: pitch positive = down).

    Attributes:
        yaw, pitch: the two axes.
        pitch_min, pitch_max: pitch joint limits [rad] (min = highest the barrel may
            point up, a negative angle; max = lowest, positive).
        limit_gain: near a pitch limit the joint velocity is bounded by
            limit_gain * (distance to the limit) [1/s], so it never drives past it.
        max_target_lead: in RATE the integrated target stays within this of the measured
            angle [rad], so a blocked or lagging gimbal does not wind its target up.
        command_topic, state_topic, imu_topic, odom_topic: topic names.
        imu_timeout, odom_timeout, joint_timeout: a sample older than this is not used [s].
        base_rate_tau: low-pass time constant of the chassis-rate estimate [s].
        odom_alignment_tau: low-pass time constant of the IMU-world <-> odom yaw offset [s].
        pivot: position of the yaw/pitch axes' crossing in base_link (x, y, z) [m].
        barrel_length: pivot to muzzle [m]; with a bullet speed the shot starts there.
        world_frames: frame ids taken as the odometry (world) frame.
        base_frames: frame ids taken as the robot frame (base_link).
        frames: the gimbal's TF frames (the first base frame is their root).
        min_track_distance: a TRACK target closer than this to the yaw axis
            (horizontally) has no defined heading; the aim is held [m].
        projectile: bullet drag and gravity for the drop compensation.
        state_rate: largest /gimbal_state publishing rate [Hz].
    """

    yaw: AxisConfig
    pitch: AxisConfig
    pitch_min: float
    pitch_max: float
    limit_gain: float
    max_target_lead: float
    command_topic: str
    state_topic: str
    imu_topic: str
    odom_topic: str
    imu_timeout: float
    odom_timeout: float
    joint_timeout: float
    base_rate_tau: float
    odom_alignment_tau: float
    pivot: tuple[float, float, float]
    barrel_length: float
    world_frames: tuple[str, ...]
    base_frames: tuple[str, ...]
    frames: FramesConfig
    min_track_distance: float
    projectile: ProjectileModel
    state_rate: float


def _axis_tuning(axis: str, max_rate: float) -> type:
    """The live keys of one axis' angle loop (``<axis>_pid.*``), with the axis' defaults."""
    def gain(default: float, unit: str, what: str, **bounds: float) -> Any:
        return declare(number, default, tunable=True, unit=unit,
                       description=f'{axis} angle loop {what}', **bounds)

    return make_dataclass(f'{axis.title()}Pid', [
        ('kp', float, gain(20.0, '1/s', 'gain: world rate per rad of error', ge=0.0)),
        ('ki', float, gain(0.0, '1/s^2', 'integral gain', ge=0.0)),
        ('kd', float, gain(0.0, '1', 'derivative gain (on the measurement)', ge=0.0)),
        ('integral_limit', float, gain(1.0, 'rad/s', 'I-term clamp', ge=0.0)),
        ('max_rate', float, gain(max_rate, 'rad/s', 'output: the largest world rate', gt=0.0)),
        ('derivative_tau', float, gain(0.0, 's', 'D-term low-pass', ge=0.0)),
    ], frozen=True, kw_only=True)


YawPid = _axis_tuning('yaw', 15.0)
PitchPid = _axis_tuning('pitch', 10.0)


@dataclass(frozen=True, kw_only=True)
class GimbalTuning:
    """What may change while the gimbal runs: its loops' gains and limits."""

    yaw_pid: Any = group(YawPid)
    pitch_pid: Any = group(PitchPid)
    yaw_max_joint_velocity: float = declare(
        number, 25.0, tunable=True, gt=0.0, unit='rad/s',
        description='largest yaw joint velocity target',
    )
    pitch_max_joint_velocity: float = declare(
        number, 20.0, tunable=True, gt=0.0, unit='rad/s',
        description='largest pitch joint velocity target',
    )
    limit_gain: float = declare(
        number, 10.0, tunable=True, gt=0.0, unit='1/s',
        description='joint velocity per rad of distance to a pitch limit',
    )
    max_target_lead: float = declare(
        number, 0.5, tunable=True, gt=0.0, unit='rad',
        description='RATE target kept within this of the measured angle',
    )


def _gains(tuning: Any) -> PidGains:
    return PidGains(
        kp=tuning.kp, ki=tuning.ki, kd=tuning.kd, integral_limit=tuning.integral_limit,
        output_limit=tuning.max_rate, derivative_tau_s=tuning.derivative_tau, angle_mode=True,
    )


def _axis(p: PluginParams, name: str, tuning: Any, max_joint_velocity: float) -> AxisConfig:
    joint = p.string(f'{name}_joint', name, description=f'{name} joint name')
    gains = loop_pid(p, f'{name}_pid', _gains(tuning), setpoint_unit='rad')
    return AxisConfig(joint, gains, max_joint_velocity)


def _retuned(loop: PidConfig, tuning: Any) -> PidConfig:
    """The loop config with the gains of tuning, in its own form (positional or incremental)."""
    gains = _gains(tuning)
    if isinstance(loop, IncrementalPidConfig):
        return incremental_like(gains, loop.setpoint_td)
    return gains


def with_tuning(config: GimbalConfig, tuning: GimbalTuning) -> GimbalConfig:
    """The config with the loops' gains and limits of tuning (set while running)."""
    yaw = AxisConfig(config.yaw.joint, _retuned(config.yaw.angle_pid, tuning.yaw_pid),
                     tuning.yaw_max_joint_velocity)
    pitch = AxisConfig(config.pitch.joint, _retuned(config.pitch.angle_pid, tuning.pitch_pid),
                       tuning.pitch_max_joint_velocity)
    return dataclasses.replace(config, yaw=yaw, pitch=pitch, limit_gain=tuning.limit_gain,
                               max_target_lead=tuning.max_target_lead)


def read_config(p: PluginParams, tuning: GimbalTuning) -> GimbalConfig:
    """Declare and read every start-up parameter; the live ones come in tuning.

    Raises:
        ParameterError: a parameter is missing, of the wrong type or out of range.
        PluginConfigError: parameters contradict each other.
    """
    yaw = _axis(p, 'yaw', tuning.yaw_pid, tuning.yaw_max_joint_velocity)
    pitch = _axis(p, 'pitch', tuning.pitch_pid, tuning.pitch_max_joint_velocity)
    if yaw.joint == pitch.joint:
        raise PluginConfigError(f'yaw_joint and pitch_joint are both {yaw.joint!r}')
    pitch_min = p.double(
        'pitch_min',
        unit='rad',
        lt=1.57,
        gt=-1.57,
        description='pitch joint limit, barrel up (negative: REP 103)',
    )
    pitch_max = p.double(
        'pitch_max',
        unit='rad',
        lt=1.57,
        gt=-1.57,
        description='pitch joint limit, barrel down (positive: REP 103)',
    )
    if not pitch_min < pitch_max:
        raise PluginConfigError(
            f'pitch_min ({pitch_min} rad) must be below pitch_max ({pitch_max} rad)'
        )
    pivot = p.vector3(
        'pivot_position',
        (0.0, 0.0, 0.0),
        unit='m',
        description='yaw/pitch axes crossing in base_link (x, y, z)',
    )
    world_frames = p.string_array(
        'world_frames',
        ('odom', 'world'),
        unique=True,
        description='frame ids taken as the odometry frame',
    )
    base_frames = p.string_array(
        'base_frames', ('base_link',), unique=True, description='frame ids taken as the robot frame'
    )
    if not base_frames:
        raise PluginConfigError('base_frames must name at least one frame (the first: base_link)')
    both = sorted(set(world_frames) & set(base_frames))
    if both:
        raise PluginConfigError(f'frame(s) {", ".join(both)} in both world_frames and base_frames')
    barrel_length = p.double(
        'barrel_length', 0.0, ge=0.0, unit='m',
        description='pivot to muzzle; bullets start at the muzzle',
    )
    return GimbalConfig(
        yaw=yaw,
        pitch=pitch,
        pitch_min=pitch_min,
        pitch_max=pitch_max,
        limit_gain=tuning.limit_gain,
        max_target_lead=tuning.max_target_lead,
        command_topic=p.string('command_topic', 'gimbal_cmd', description='GimbalCmd input'),
        state_topic=p.string('state_topic', 'gimbal_state', description='GimbalState output'),
        imu_topic=p.string('imu_topic', 'imu', description='sensor_msgs/Imu of the gimbal IMU'),
        odom_topic=p.string('odom_topic', 'odom', description='nav_msgs/Odometry of the chassis'),
        imu_timeout=p.double(
            'imu_timeout',
            0.2,
            gt=0.0,
            unit='s',
            description='an IMU sample older than this is not used',
        ),
        odom_timeout=p.double(
            'odom_timeout',
            0.2,
            gt=0.0,
            unit='s',
            description='odometry older than this is not used',
        ),
        joint_timeout=p.double(
            'joint_timeout',
            0.2,
            gt=0.0,
            unit='s',
            description='a joint state older than this is not used',
        ),
        base_rate_tau=p.double(
            'base_rate_tau',
            0.01,
            ge=0.0,
            unit='s',
            description='low-pass of the chassis-rate estimate',
        ),
        odom_alignment_tau=p.double(
            'odom_alignment_tau',
            0.5,
            ge=0.0,
            unit='s',
            description='low-pass of the IMU-world/odom yaw offset',
        ),
        pivot=pivot,
        barrel_length=barrel_length,
        world_frames=world_frames,
        base_frames=base_frames,
        frames=read_frames(p, base_frames[0], barrel_length),
        min_track_distance=p.double(
            'min_track_distance',
            0.1,
            gt=0.0,
            unit='m',
            description='closer TRACK targets hold the aim',
        ),
        projectile=ProjectileModel(
            drag=p.double(
                'bullet_drag',
                0.0,
                ge=0.0,
                unit='1/m',
                description='quadratic drag coefficient k of the bullet',
            ),
            gravity=p.double(
                'gravity',
                STANDARD_GRAVITY,
                gt=0.0,
                unit='m/s^2',
                description='gravitational acceleration',
            ),
        ),
        state_rate=p.double(
            'state_rate', 100.0, gt=0.0, unit='Hz', description='largest /gimbal_state rate'
        ),
    )
