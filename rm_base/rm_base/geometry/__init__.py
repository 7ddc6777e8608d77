"""Geometry: angles, encoder unwrapping, rotations, rigid transforms, wheel kinematics.

No ROS, no I/O, no threads. SI units and REP 103 frames (x forward, y left, z up);
quaternions in ROS order (x, y, z, w). Bad runtime input raises
``rm_base.errors.InputRejectedError``, bad configuration ``rm_base.errors.ConfigError``.
"""

from rm_base.geometry.angles import TAU, shortest_angular_distance, wrap_to_2pi, wrap_to_pi
from rm_base.geometry.encoder import DJI_TICKS_PER_REV, EncoderUnwrapper, rotor_to_output
from rm_base.geometry.kinematics import (
    MECANUM_ROLLER_SIGNS,
    Twist2D,
    Wheel,
    WheelKinematics,
    body_to_world_twist,
    desaturate,
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
from rm_base.geometry.transforms import SE2, SE3

__all__ = [
    'DJI_TICKS_PER_REV',
    'MECANUM_ROLLER_SIGNS',
    'SE2',
    'SE3',
    'TAU',
    'EncoderUnwrapper',
    'Quaternion',
    'Twist2D',
    'Wheel',
    'WheelKinematics',
    'body_to_world_twist',
    'desaturate',
    'mecanum_wheels',
    'normalize_quaternion',
    'omni_wheels',
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
    'world_to_body_twist',
    'wrap_to_2pi',
    'wrap_to_pi',
    'yaw_from_quaternion',
]
