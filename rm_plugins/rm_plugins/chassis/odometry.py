"""Planar odometry of the chassis: wheel forward kinematics, yaw from an IMU when there is one.

The pose of base_link in odom (x, y [m], yaw [rad]) starts at zero and is integrated each
step with the midpoint heading. The twist comes from the wheels' forward kinematics
(least squares, so one slipping wheel is outvoted by the others). The yaw comes from

- an absolute yaw (the IMU's, turned into the chassis' yaw by the caller) while one is
  given: the first one after none fixes the offset between the IMU's heading reference
  and odom, so the yaw stays continuous when the source changes; or
- the wheels' yaw rate integrated, while none is given.

The yaw is kept unwrapped (continuous) so a spinning robot's heading can be compared over
many turns; ``Odometry.pose`` gives it as is. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from enum import Enum
from typing import NamedTuple

from rm_base.errors import InputRejectedError
from rm_base.geometry import Twist2D, WheelKinematics, body_to_world_twist, wrap_to_pi


class YawSource(Enum):
    """Where the odometry yaw of the last step came from."""

    WHEELS = 'wheels'
    IMU = 'imu'


class Pose2D(NamedTuple):
    """A planar pose: x, y [m] and yaw [rad] (unwrapped)."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0


class Odometry:
    """Integrates the chassis pose from wheel speeds and an optional absolute yaw.

    Args:
        kinematics: the wheels, in the order of the wheel speeds given to ``update``.
    """

    def __init__(self, kinematics: WheelKinematics) -> None:
        self._kinematics = kinematics
        self._pose = Pose2D()
        self._twist = Twist2D()
        self._yaw_offset: float | None = None
        self._source = YawSource.WHEELS

    @property
    def pose(self) -> Pose2D:
        """Pose of base_link in odom after the last update."""
        return self._pose

    @property
    def twist(self) -> Twist2D:
        """Twist of base_link in base_link from the last wheel speeds [m/s, m/s, rad/s]."""
        return self._twist

    @property
    def yaw_source(self) -> YawSource:
        """Source of the yaw in the last update."""
        return self._source

    def reset(self, pose: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        """Restart at pose (x [m], y [m], yaw [rad]); the next absolute yaw sets a new offset."""
        x, y, yaw = (float(v) for v in pose)
        if not all(math.isfinite(v) for v in (x, y, yaw)):
            raise InputRejectedError(f'pose must be 3 finite values, got {pose!r}')
        self._pose = Pose2D(x, y, yaw)
        self._twist = Twist2D()
        self._yaw_offset = None
        self._source = YawSource.WHEELS

    def update(
        self, wheel_speeds: Sequence[float], dt: float, absolute_yaw: float | None = None
    ) -> Pose2D:
        """Advance the pose by dt with the wheel speeds measured now.

        Args:
            wheel_speeds: one speed per wheel [rad/s], in wheel order.
            dt: time since the previous update [s], finite and >= 0 (0 only updates the
                twist).
            absolute_yaw: chassis yaw from an external reference (IMU) [rad], any offset;
                None to integrate the wheels' yaw rate.

        Returns:
            The new pose.

        Raises:
            InputRejectedError: a speed, dt or absolute_yaw is not finite, dt < 0, or the
                number of speeds is wrong. The pose is left as it was.
        """
        if not 0.0 <= dt < math.inf:
            raise InputRejectedError(f'dt must be finite and >= 0 s, got {dt!r}')
        if absolute_yaw is not None and not math.isfinite(absolute_yaw):
            raise InputRejectedError(f'absolute yaw must be finite, got {absolute_yaw!r}')
        twist = self._kinematics.forward(wheel_speeds)
        x, y, yaw = self._pose
        if absolute_yaw is None:
            self._yaw_offset = None
            self._source = YawSource.WHEELS
            new_yaw = yaw + twist.wz * dt
        else:
            if self._yaw_offset is None:
                # First absolute yaw after none: tie its reference to the current odom yaw.
                self._yaw_offset = absolute_yaw - yaw
            self._source = YawSource.IMU
            # Shortest way from the current (unwrapped) yaw, so the yaw stays continuous.
            new_yaw = yaw + wrap_to_pi(absolute_yaw - self._yaw_offset - yaw)
        vx, vy, _ = body_to_world_twist((twist.vx, twist.vy, 0.0), 0.5 * (yaw + new_yaw))
        self._pose = Pose2D(x + vx * dt, y + vy * dt, new_yaw)
        self._twist = twist
        return self._pose
