"""Geometry: angles, encoders, rotations, transforms, kinematics, ballistics, aiming.

No ROS, no I/O, no threads. SI units and REP 103 frames (x forward, y left, z up);
quaternions in ROS order (x, y, z, w). Bad runtime input raises
``rm_base.errors.InputRejectedError``, bad configuration ``rm_base.errors.ConfigError``.
"""

from rm_base.geometry.aim import (
    AimSolution,
    GimbalMount,
    aim_at,
    aim_from_point,
    pitch_axis_in_world,
)
from rm_base.geometry.angles import TAU, shortest_angular_distance, wrap_to_2pi, wrap_to_pi
from rm_base.geometry.ballistics import (
    STANDARD_GRAVITY,
    BallisticSolution,
    ProjectileModel,
    solve_ballistic,
    trajectory_height,
)
from rm_base.geometry.encoder import DJI_TICKS_PER_REV, EncoderUnwrapper, rotor_to_output
from rm_base.geometry.kinematics import (
    MECANUM_ROLLER_SIGNS,
    Twist2D,
    Wheel,
    WheelKinematics,
    body_to_world_twist,
    desaturate,
    desaturate_speeds,
    mecanum_wheels,
    omni_wheels,
    world_to_body_twist,
)
from rm_base.geometry.rotations import (
    Quaternion,
    normalize_quaternion,
    quaternion_from_rotation_matrix,
    quaternion_from_rpy,
    quaternion_from_yaw,
    quaternion_inverse,
    quaternion_multiply,
    rotation_matrix_from_quaternion,
    rotation_matrix_from_rpy,
    rpy_from_quaternion,
    yaw_from_quaternion,
)
from rm_base.geometry.swerve import (
    ModuleState,
    SwerveKinematics,
    SwerveModule,
    nearest_module_state,
    square_modules,
)
from rm_base.geometry.transforms import SE2, SE3

__all__ = [
    'DJI_TICKS_PER_REV',
    'MECANUM_ROLLER_SIGNS',
    'SE2',
    'SE3',
    'STANDARD_GRAVITY',
    'TAU',
    'AimSolution',
    'BallisticSolution',
    'EncoderUnwrapper',
    'GimbalMount',
    'ModuleState',
    'ProjectileModel',
    'Quaternion',
    'SwerveKinematics',
    'SwerveModule',
    'Twist2D',
    'Wheel',
    'WheelKinematics',
    'aim_at',
    'aim_from_point',
    'body_to_world_twist',
    'desaturate',
    'desaturate_speeds',
    'mecanum_wheels',
    'nearest_module_state',
    'normalize_quaternion',
    'omni_wheels',
    'pitch_axis_in_world',
    'quaternion_from_rotation_matrix',
    'quaternion_from_rpy',
    'quaternion_from_yaw',
    'quaternion_inverse',
    'quaternion_multiply',
    'rotation_matrix_from_quaternion',
    'rotation_matrix_from_rpy',
    'rotor_to_output',
    'rpy_from_quaternion',
    'shortest_angular_distance',
    'solve_ballistic',
    'square_modules',
    'trajectory_height',
    'world_to_body_twist',
    'wrap_to_2pi',
    'wrap_to_pi',
    'yaw_from_quaternion',
]
