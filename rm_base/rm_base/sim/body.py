"""Robot body driven by the simulated motors: planar chassis pose and a yaw/pitch gimbal.

Frames follow REP 103 (x forward, y left, z up); angles in rad, positive counter-clockwise
about the axis (positive pitch noses down).

* Chassis: the wheels' output-shaft speeds (times each wheel's ``direction``) go through
  the forward wheel kinematics of :mod:`rm_base.geometry.kinematics` (ideal, no slip;
  least squares when the wheels disagree) to a body twist, integrated into the world pose
  (x, y, yaw) with the midpoint heading. A swerve chassis' wheels roll where their
  steering joints point them (:mod:`rm_base.geometry.swerve`, the same least squares).
* Gimbal: yaw and pitch joint angles are ``direction * (motor angle - zero)``. The yaw
  motor's stator turns with the chassis while its load keeps its inertia in the world, so
  the chassis' yaw acceleration is fed to that motor (``world_frame_inertia``). The pitch
  joint can carry a gravity torque ``gravity_torque * cos(pitch)`` (nose-heavy > 0) and
  rests on its mechanical end stops (``end_stops``): a joint pushed past one is put back on
  it with no speed outward, an inelastic stop.
* Orientation of a body: chassis ``Rz(yaw)``; gimbal ``Rz(yaw + yaw_joint) Ry(pitch_joint)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from enum import Enum

import numpy as np
from numpy.typing import NDArray

from rm_base.geometry import SwerveKinematics, WheelKinematics, rotation_matrix_from_rpy
from rm_base.sim.joint import Joint
from rm_base.sim.launcher import Launcher
from rm_base.sim_devices.device import SimDevice
from rm_base.sim_devices.errors import SimConfigError


class Mount(Enum):
    """The rigid body a sensor is fixed to."""

    CHASSIS = 'chassis'
    GIMBAL = 'gimbal'


class Chassis:
    """The wheels that move the body, and how: fixed wheels, or steered ones (swerve).

    Args:
        kinematics: fixed wheels' kinematics, or a swerve chassis' modules.
        wheels: the wheel (drive) motors, in the kinematics' order.
        directions: wheel speed = direction x motor speed; default all 1.
        steering: a swerve chassis' steering joints (module angle), one per wheel.

    Raises:
        SimConfigError: the counts disagree, a direction is not ±1, or steering joints
            for fixed wheels (or none for swerve modules).
    """

    def __init__(
        self,
        kinematics: WheelKinematics | SwerveKinematics,
        wheels: Sequence[SimDevice],
        directions: Sequence[float] | None = None,
        steering: Sequence[Joint] = (),
    ) -> None:
        count = (
            len(kinematics.modules) if isinstance(kinematics, SwerveKinematics)
            else len(kinematics.wheels)
        )
        if len(wheels) != count:
            raise SimConfigError(f'{count} wheels in the kinematics, {len(wheels)} motors')
        directions = [1.0] * count if directions is None else list(directions)
        if len(directions) != count or any(d not in (1, -1) for d in directions):
            raise SimConfigError(f'wheel directions must be one ±1 per wheel, got {directions}')
        swerve = isinstance(kinematics, SwerveKinematics)
        if swerve and len(steering) != count:
            raise SimConfigError(
                f'a swerve chassis needs one steering joint per module ({count}), '
                f'got {len(steering)}'
            )
        if not swerve and steering:
            raise SimConfigError('fixed wheels have no steering joints')
        self.kinematics = kinematics
        self.wheels = tuple(wheels)
        self.directions = tuple(float(d) for d in directions)
        self.steering = tuple(steering)

    @property
    def motors(self) -> tuple[SimDevice, ...]:
        """Every motor of the chassis (wheels, then steering): its power output."""
        return self.wheels + tuple(j.device for j in self.steering)

    def twist(self) -> tuple[float, float, float]:
        """The body twist (vx, vy [m/s], wz [rad/s]) the wheels give now."""
        # Plain floats: four speeds every tick cost less than building an array.
        speeds = [w.model.velocity * d for w, d in zip(self.wheels, self.directions, strict=True)]
        kinematics = self.kinematics
        if isinstance(kinematics, SwerveKinematics):
            vx, vy, wz = kinematics.forward([j.angle for j in self.steering], speeds)
        else:
            vx, vy, wz = kinematics.forward(speeds)
        return vx, vy, wz


class RobotBody:
    """Pose of the chassis and gimbal, advanced from the motors' motion.

    Attributes:
        x: chassis position in the world [m].
        y: chassis position in the world [m].
        yaw: chassis heading in the world [rad], unwrapped.
        twist: chassis velocity in its own frame (vx, vy [m/s], wz [rad/s]).
        yaw_acceleration: chassis angular acceleration [rad/s²] over the last step.
        linear_acceleration: chassis acceleration in the world (ax, ay) [m/s²].
        pitch_gravity_torque: gravity torque on the pitch joint at 0 pitch [N·m].
        pitch_end_stops: the pitch joint's mechanical stops (low, high) [rad], or None.
        yaw_world_frame_inertia: feed the chassis' yaw acceleration to the yaw motor.
        launcher: the shooter's mechanics (which trigger pushes are shots), or None.
    """

    def __init__(
        self,
        *,
        chassis: Chassis | None = None,
        yaw: Joint | None = None,
        pitch: Joint | None = None,
        initial_pose: Sequence[float] = (0.0, 0.0, 0.0),
        pitch_gravity_torque: float = 0.0,
        pitch_end_stops: Sequence[float] | None = None,
        yaw_world_frame_inertia: bool = True,
        launcher: Launcher | None = None,
    ):
        """Create the body (:func:`rm_base.sim.body_config.body_from_config` reads a config).

        Raises:
            SimConfigError: a bad pose.
        """
        if len(initial_pose) != 3 or not all(math.isfinite(v) for v in initial_pose):
            raise SimConfigError(f'initial_pose must be 3 finite numbers, got {initial_pose!r}')
        self.chassis = chassis
        self.yaw_joint = yaw
        self.pitch_joint = pitch
        self.x, self.y, self.yaw = (float(v) for v in initial_pose)
        self.pitch_gravity_torque = float(pitch_gravity_torque)
        self.pitch_end_stops = None if pitch_end_stops is None else (
            float(pitch_end_stops[0]), float(pitch_end_stops[1]))
        self.yaw_world_frame_inertia = yaw_world_frame_inertia
        self.launcher = launcher
        self.twist = self._chassis_twist()
        self.yaw_acceleration = 0.0
        self.linear_acceleration = (0.0, 0.0)
        self._world_velocity = self._to_world(self.twist[0], self.twist[1], self.yaw)

    @property
    def wheels(self) -> tuple[SimDevice, ...]:
        """The chassis' wheel (drive) motors, none without a chassis."""
        return () if self.chassis is None else self.chassis.wheels

    # -- stepping (called by the world) ----------------------------------------------------

    @property
    def late_devices(self) -> tuple[SimDevice, ...]:
        """Motors to step after the chassis (they need its yaw acceleration)."""
        if self.yaw_joint is not None and self.yaw_world_frame_inertia:
            return (self.yaw_joint.device,)
        return ()

    def apply_loads(self) -> None:
        """Set the gravity torque on the pitch motor for the coming step."""
        joint = self.pitch_joint
        if joint is not None and self.pitch_gravity_torque:
            torque = self.pitch_gravity_torque * math.cos(joint.angle)
            joint.device.model.external_torque = joint.direction * torque

    def apply_end_stops(self) -> None:
        """Put a pitch joint that passed a mechanical stop back on it (after a step)."""
        joint, stops = self.pitch_joint, self.pitch_end_stops
        if joint is None or stops is None:
            return
        angle, velocity = joint.angle, joint.velocity
        if stops[0] <= angle <= stops[1]:
            return
        stop = stops[0] if angle < stops[0] else stops[1]
        outward = velocity < 0.0 if angle < stops[0] else velocity > 0.0
        model = joint.device.model
        g = model.params.gear_ratio
        # joint angle = direction * (output angle - zero); the rotor turns g times the output
        model.rotor_angle = (joint.zero + stop / joint.direction) * g
        if outward:
            model.rotor_velocity = 0.0

    def update_chassis(self, dt: float) -> None:
        """Integrate the chassis pose over dt [s] from the wheels' current speeds."""
        old_wz = self.twist[2]
        twist = self._chassis_twist()
        vx, vy, wz = twist
        heading = self.yaw + 0.5 * wz * dt
        dx, dy = self._to_world(vx, vy, heading)
        self.x += dx * dt
        self.y += dy * dt
        self.yaw += wz * dt
        world_velocity = self._to_world(vx, vy, self.yaw)
        self.linear_acceleration = (
            (world_velocity[0] - self._world_velocity[0]) / dt,
            (world_velocity[1] - self._world_velocity[1]) / dt,
        )
        self.yaw_acceleration = (wz - old_wz) / dt
        self._world_velocity = world_velocity
        self.twist = twist

    def _chassis_twist(self) -> tuple[float, float, float]:
        return (0.0, 0.0, 0.0) if self.chassis is None else self.chassis.twist()

    @staticmethod
    def _to_world(vx: float, vy: float, heading: float) -> tuple[float, float]:
        c, s = math.cos(heading), math.sin(heading)
        return (c * vx - s * vy, s * vx + c * vy)

    # -- queries ---------------------------------------------------------------------------

    @property
    def gimbal_yaw(self) -> float:
        """Yaw joint angle relative to the chassis [rad] (0 without a yaw joint)."""
        return self.yaw_joint.angle if self.yaw_joint is not None else 0.0

    @property
    def gimbal_pitch(self) -> float:
        """Pitch joint angle [rad] (0 without a pitch joint); positive noses down."""
        return self.pitch_joint.angle if self.pitch_joint is not None else 0.0

    def attitude(self, mount: Mount) -> tuple[float, float, float]:
        """(roll, pitch, yaw) [rad] of the chassis or the gimbal in the world frame."""
        if mount is Mount.CHASSIS:
            return (0.0, 0.0, self.yaw)
        return (0.0, self.gimbal_pitch, self.yaw + self.gimbal_yaw)

    def orientation(self, mount: Mount) -> NDArray[np.float64]:
        """Rotation matrix world <- body of the chassis or the gimbal."""
        return rotation_matrix_from_rpy(*self.attitude(mount))

    def angular_velocity(self, mount: Mount) -> NDArray[np.float64]:
        """Angular velocity of the chassis or gimbal in the world frame [rad/s]."""
        wz = self.twist[2]
        if mount is Mount.CHASSIS:
            return np.array([0.0, 0.0, wz])
        yaw_rate = self.yaw_joint.velocity if self.yaw_joint is not None else 0.0
        pitch_rate = self.pitch_joint.velocity if self.pitch_joint is not None else 0.0
        heading = self.yaw + self.gimbal_yaw
        # The pitch axis is the gimbal's y axis after the yaw rotation.
        return np.array(
            [-math.sin(heading) * pitch_rate, math.cos(heading) * pitch_rate, wz + yaw_rate]
        )

    def world_acceleration(self) -> NDArray[np.float64]:
        """Linear acceleration of the chassis in the world frame [m/s²] (z = 0)."""
        return np.array([self.linear_acceleration[0], self.linear_acceleration[1], 0.0])
