"""Robot body driven by the simulated motors: planar chassis pose and a yaw/pitch gimbal.

Frames follow REP 103 (x forward, y left, z up); angles in rad, positive counter-clockwise
about the axis (positive pitch noses down).

* Chassis: the wheels' output-shaft speeds (times each wheel's ``direction``) go through
  the forward wheel kinematics of :mod:`rm_base.geometry.kinematics` (ideal, no slip;
  least squares when the wheels disagree) to a body twist, integrated into the world pose
  (x, y, yaw) with the midpoint heading.
* Gimbal: yaw and pitch joint angles are ``direction * (motor angle - zero)``. The yaw
  motor's stator turns with the chassis while its load keeps its inertia in the world, so
  the chassis' yaw acceleration is fed to that motor (``world_frame_inertia``). The pitch
  joint can carry a gravity torque ``gravity_torque * cos(pitch)`` (nose-heavy > 0).
* Orientation of a body: chassis ``Rz(yaw)``; gimbal ``Rz(yaw + yaw_joint) Ry(pitch_joint)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from enum import Enum
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rm_base.errors import ConfigError
from rm_base.geometry import (
    Wheel,
    WheelKinematics,
    mecanum_wheels,
    omni_wheels,
    rotation_matrix_from_rpy,
)
from rm_base.sim.devices import SimDevice
from rm_base.sim.errors import SimConfigError
from rm_base.sim.joint import (
    Joint,
    check_keys,
    config_number,
    direction_from_config,
    joint_from_config,
    motor_from_config,
)
from rm_base.sim.launcher import Launcher, launcher_from_config


class Mount(Enum):
    """The rigid body a sensor is fixed to."""

    CHASSIS = 'chassis'
    GIMBAL = 'gimbal'


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
        yaw_world_frame_inertia: feed the chassis' yaw acceleration to the yaw motor.
        launcher: the shooter's mechanics (which trigger pushes are shots), or None.
    """

    def __init__(
        self,
        *,
        kinematics: WheelKinematics | None = None,
        wheels: Sequence[SimDevice] = (),
        wheel_directions: Sequence[float] | None = None,
        yaw: Joint | None = None,
        pitch: Joint | None = None,
        initial_pose: Sequence[float] = (0.0, 0.0, 0.0),
        pitch_gravity_torque: float = 0.0,
        yaw_world_frame_inertia: bool = True,
        launcher: Launcher | None = None,
    ):
        """Create the body; see :func:`body_from_config` for the parameters.

        Raises:
            SimConfigError: wheels and kinematics disagree in number, or a bad pose.
        """
        if (kinematics is None) != (not wheels):
            raise SimConfigError('a chassis needs both kinematics and wheel motors')
        if kinematics is not None and len(kinematics.wheels) != len(wheels):
            raise SimConfigError(
                f'{len(kinematics.wheels)} wheels in the kinematics, {len(wheels)} motors'
            )
        directions = [1.0] * len(wheels) if wheel_directions is None else wheel_directions
        if len(directions) != len(wheels) or any(d not in (1, -1) for d in directions):
            raise SimConfigError(f'wheel directions must be one ±1 per wheel, got {directions}')
        if len(initial_pose) != 3 or not all(math.isfinite(v) for v in initial_pose):
            raise SimConfigError(f'initial_pose must be 3 finite numbers, got {initial_pose!r}')
        self.kinematics = kinematics
        self.wheels = tuple(wheels)
        self.wheel_directions = np.array(directions, dtype=float)
        self._directions = tuple(float(d) for d in directions)
        self.yaw_joint = yaw
        self.pitch_joint = pitch
        self.x, self.y, self.yaw = (float(v) for v in initial_pose)
        self.pitch_gravity_torque = float(pitch_gravity_torque)
        self.yaw_world_frame_inertia = yaw_world_frame_inertia
        self.launcher = launcher
        self.twist = self._chassis_twist()
        self.yaw_acceleration = 0.0
        self.linear_acceleration = (0.0, 0.0)
        self._world_velocity = self._to_world(self.twist[0], self.twist[1], self.yaw)

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
        if self.kinematics is None:
            return (0.0, 0.0, 0.0)
        # Plain floats: four speeds every tick cost less than building an array.
        speeds = [w.model.velocity * d for w, d in zip(self.wheels, self._directions, strict=True)]
        vx, vy, wz = self.kinematics.forward(speeds)
        return vx, vy, wz

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


# -- config ----------------------------------------------------------------------------------


def _chassis(
    cfg: Mapping[str, Any], devices: Mapping[str, SimDevice]
) -> tuple[WheelKinematics, list[SimDevice], list[float]]:
    kind = cfg.get('type')
    common = {'type', 'motors', 'directions'}
    if kind == 'mecanum':
        check_keys(cfg, common | {'wheelbase', 'track', 'wheel_radius', 'roller_signs'}, 'chassis')
        extra = {'roller_signs': cfg['roller_signs']} if 'roller_signs' in cfg else {}
        wheels = mecanum_wheels(
            config_number(cfg, 'wheelbase', 'chassis'),
            config_number(cfg, 'track', 'chassis'),
            config_number(cfg, 'wheel_radius', 'chassis'),
            **extra,
        )
    elif kind == 'omni':
        check_keys(cfg, common | {'mounting_angles', 'centre_distance', 'wheel_radius'}, 'chassis')
        wheels = omni_wheels(
            cfg.get('mounting_angles', ()),
            config_number(cfg, 'centre_distance', 'chassis'),
            config_number(cfg, 'wheel_radius', 'chassis'),
        )
    elif kind == 'wheels':
        check_keys(cfg, {'type', 'wheels'}, 'chassis')
        return _explicit_wheels(cfg.get('wheels'), devices)
    else:
        raise SimConfigError(f"chassis.type must be 'mecanum', 'omni' or 'wheels', got {kind!r}")
    names = cfg.get('motors')
    if not isinstance(names, Sequence) or isinstance(names, str) or len(names) != len(wheels):
        raise SimConfigError(f'chassis.motors must name {len(wheels)} motors, got {names!r}')
    directions = cfg.get('directions', [1] * len(wheels))
    if not isinstance(directions, Sequence) or len(directions) != len(wheels):
        raise SimConfigError(f'chassis.directions must be {len(wheels)} of ±1, got {directions!r}')
    return (
        WheelKinematics(wheels),
        [motor_from_config(devices, n, 'chassis.motors') for n in names],
        [direction_from_config(d, 'chassis') for d in directions],
    )


def _explicit_wheels(
    entries: Any, devices: Mapping[str, SimDevice]
) -> tuple[WheelKinematics, list[SimDevice], list[float]]:
    if not isinstance(entries, Sequence) or isinstance(entries, str):
        raise SimConfigError(f'chassis.wheels must be a list, got {entries!r}')
    allowed = {'motor', 'x', 'y', 'radius', 'rolling_direction', 'roller_angle', 'direction'}
    wheels, motors, directions = [], [], []
    for i, entry in enumerate(entries):
        owner = f'chassis.wheels[{i}]'
        check_keys(entry, allowed, owner)
        wheels.append(
            Wheel(
                config_number(entry, 'x', owner),
                config_number(entry, 'y', owner),
                config_number(entry, 'radius', owner),
                rolling_direction=config_number(entry, 'rolling_direction', owner, 0.0),
                roller_angle=config_number(entry, 'roller_angle', owner, 0.0),
            )
        )
        motors.append(motor_from_config(devices, entry.get('motor'), owner))
        directions.append(direction_from_config(entry.get('direction', 1), owner))
    return WheelKinematics(wheels), motors, directions


def body_from_config(config: Mapping[str, Any], devices: Mapping[str, SimDevice]) -> RobotBody:
    """Build the body from a plain dict; motors are referred to by name.

    Schema (SI units, every part optional)::

        initial_pose: [x, y, yaw]                # m, m, rad
        chassis:                                  # wheel i speed = direction_i * motor speed
          type: mecanum                           # FL, FR, RL, RR (rm_base.geometry layout)
          motors: [wheel_fl, wheel_fr, wheel_rl, wheel_rr]
          wheelbase: 0.4                          # m
          track: 0.4                              # m
          wheel_radius: 0.076                     # m
          roller_signs: [-1, 1, 1, -1]            # optional
          directions: [1, -1, 1, -1]              # optional, default all 1
        # or type: omni with mounting_angles [rad], centre_distance [m], wheel_radius, motors
        # or type: wheels with wheels: [{motor, x, y, radius, rolling_direction,
        #                                roller_angle, direction}, ...]
        gimbal:
          yaw: {motor: yaw, direction: 1, zero: 0.0, world_frame_inertia: true}
          pitch: {motor: pitch, direction: 1, zero: 0.0, gravity_torque: 0.0}   # N·m
        shooter: {trigger: ..., friction: [...], ...}   # rm_base.sim.launcher

    Args:
        config: the ``body`` dict of a world config.
        devices: every configured motor by name.

    Returns:
        The body.

    Raises:
        SimConfigError: an unknown key, a missing or unknown motor, bad geometry.
    """
    check_keys(config, {'initial_pose', 'chassis', 'gimbal', 'shooter'}, 'body')
    try:
        kinematics: WheelKinematics | None = None
        wheels: list[SimDevice] = []
        directions: list[float] | None = None
        if 'chassis' in config:
            if not isinstance(config['chassis'], Mapping):
                raise SimConfigError(f'chassis must be a mapping, got {config["chassis"]!r}')
            kinematics, wheels, directions = _chassis(config['chassis'], devices)
        yaw = pitch = None
        gravity, world_frame = 0.0, True
        gimbal = config.get('gimbal', {})
        check_keys(gimbal, {'yaw', 'pitch'}, 'gimbal')
        if 'yaw' in gimbal:
            yaw = joint_from_config(gimbal['yaw'], devices, 'gimbal.yaw', {'world_frame_inertia'})
            world_frame = gimbal['yaw'].get('world_frame_inertia', True)
            if not isinstance(world_frame, bool):
                raise SimConfigError(
                    f'gimbal.yaw.world_frame_inertia must be true/false, got {world_frame!r}'
                )
        if 'pitch' in gimbal:
            pitch = joint_from_config(gimbal['pitch'], devices, 'gimbal.pitch', {'gravity_torque'})
            gravity = config_number(gimbal['pitch'], 'gravity_torque', 'gimbal.pitch', 0.0)
        pose = config.get('initial_pose', (0.0, 0.0, 0.0))
        if not isinstance(pose, Sequence) or isinstance(pose, str):
            raise SimConfigError(f'initial_pose must be [x, y, yaw], got {pose!r}')
        return RobotBody(
            kinematics=kinematics,
            wheels=wheels,
            wheel_directions=directions,
            yaw=yaw,
            pitch=pitch,
            initial_pose=pose,
            pitch_gravity_torque=gravity,
            yaw_world_frame_inertia=world_frame,
            launcher=launcher_from_config(config['shooter'], devices)
            if 'shooter' in config
            else None,
        )
    except SimConfigError:
        raise
    except ConfigError as err:
        raise SimConfigError(f'body: {err}') from err
