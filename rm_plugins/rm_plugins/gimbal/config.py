"""StandGimbal configuration: one frozen dataclass read from the plugin's parameters."""

from __future__ import annotations

from dataclasses import dataclass

from rm_base.control import PidConfig, PidGains
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


def _axis(p: PluginParams, name: str, default_joint: str, defaults: dict[str, float]) -> AxisConfig:
    joint = p.string(f'{name}_joint', default_joint, description=f'{name} joint name')
    key = f'{name}_pid'
    positional = PidGains(
        kp=p.double(
            f'{key}.kp',
            defaults['kp'],
            ge=0.0,
            unit='1/s',
            description=f'{name} angle loop: world rate per rad of error',
        ),
        ki=p.double(
            f'{key}.ki',
            defaults['ki'],
            ge=0.0,
            unit='1/s^2',
            description=f'{name} angle loop integral gain',
        ),
        kd=p.double(
            f'{key}.kd',
            defaults['kd'],
            ge=0.0,
            unit='1',
            description=f'{name} angle loop derivative gain (on the measurement)',
        ),
        integral_limit=p.double(
            f'{key}.integral_limit',
            defaults['integral_limit'],
            ge=0.0,
            unit='rad/s',
            description=f'{name} angle loop I-term clamp',
        ),
        output_limit=p.double(
            f'{key}.max_rate',
            defaults['max_rate'],
            gt=0.0,
            unit='rad/s',
            description=f'largest {name} rate in the world frame',
        ),
        derivative_tau_s=p.double(
            f'{key}.derivative_tau',
            0.0,
            ge=0.0,
            unit='s',
            description=f'{name} angle loop D-term low-pass',
        ),
        angle_mode=True,
    )
    gains = loop_pid(p, key, positional, setpoint_unit='rad')
    max_velocity = p.double(
        f'{name}_max_joint_velocity',
        defaults['max_joint_velocity'],
        gt=0.0,
        unit='rad/s',
        description=f'largest {name} joint velocity target',
    )
    return AxisConfig(joint, gains, max_velocity)


def read_config(p: PluginParams) -> GimbalConfig:
    """Declare and read every parameter of the plugin.

    Raises:
        ParameterError: a parameter is missing, of the wrong type or out of range.
        PluginConfigError: parameters contradict each other.
    """
    yaw = _axis(
        p,
        'yaw',
        'yaw',
        {
            'kp': 20.0,
            'ki': 0.0,
            'kd': 0.0,
            'integral_limit': 1.0,
            'max_rate': 15.0,
            'max_joint_velocity': 25.0,
        },
    )
    pitch = _axis(
        p,
        'pitch',
        'pitch',
        {
            'kp': 20.0,
            'ki': 0.0,
            'kd': 0.0,
            'integral_limit': 1.0,
            'max_rate': 10.0,
            'max_joint_velocity': 20.0,
        },
    )
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
        limit_gain=p.double(
            'limit_gain',
            10.0,
            gt=0.0,
            unit='1/s',
            description='joint velocity per rad of distance to a pitch limit',
        ),
        max_target_lead=p.double(
            'max_target_lead',
            0.5,
            gt=0.0,
            unit='rad',
            description='RATE target kept within this of the measured angle',
        ),
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
