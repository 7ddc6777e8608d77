"""Planar odometry of the chassis: wheel forward kinematics, yaw from an IMU when there is one.

The pose of base_link in odom (x, y [m], yaw [rad]) starts at zero. Each step moves it by
the forward kinematics (least squares, so one slipping wheel is outvoted by the others) of
the wheels' *angle* changes since the previous step, along the midpoint heading. Angle
changes, not speed times dt: the encoders count every radian whatever the timing, so a
late or skipped step (CPU steal, a dropped feedback message) loses no distance, where
integrating speeds over the plugin's own dt would. The twist comes from the wheel speeds.
The yaw comes from

- an absolute yaw (the IMU's, turned into the chassis' yaw by the caller) while one is
  given: the first one fixes the offset between the IMU's heading reference and odom, so
  the yaw starts continuous; or
- the wheels' turn (their angle changes) while none is given.

The offset is kept through gaps in the absolute yaw, so after a short gap the yaw returns
to the IMU's (the better heading: the wheels slip) instead of keeping the wheels' error.
After a long gap (the IMU may have restarted with a new reference) the caller calls
``release_absolute_yaw`` and the next one fixes a new offset.

The yaw is kept unwrapped (continuous) so a spinning robot's heading can be compared over
many turns; ``Odometry.pose`` gives it as is. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from enum import Enum
from typing import NamedTuple

from rm_base.errors import InputRejectedError
from rm_base.geometry import Twist2D, body_to_world_twist, wrap_to_pi

from rm_plugins.chassis.drive import Drive


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

    def __init__(self, kinematics: Drive) -> None:
        self._kinematics = kinematics
        self._pose = Pose2D()
        self._twist = Twist2D()
        self._yaw_offset: float | None = None
        self._source = YawSource.WHEELS
        self._angles: tuple[float, ...] | None = None

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
        """Restart at pose (x [m], y [m], yaw [rad]).

        The next update only takes the wheel angles as the new reference, and the next
        absolute yaw sets a new offset.
        """
        x, y, yaw = (float(v) for v in pose)
        if not all(map(math.isfinite, (x, y, yaw))):
            raise InputRejectedError(f'pose must be 3 finite values, got {pose!r}')
        self._pose = Pose2D(x, y, yaw)
        self._twist = Twist2D()
        self._yaw_offset = None
        self._source = YawSource.WHEELS
        self._angles = None

    @property
    def wheel_angles(self) -> tuple[float, ...] | None:
        """The wheel angles of the last update (the reference of the next step) [rad]."""
        return self._angles

    def restart_wheel_reference(self) -> None:
        """Take the next wheel angles as the reference without moving.

        For when the angles may have jumped: the encoders' multi-turn count restarts with
        the bridge, so motion across a long gap in the feedback cannot be told from a
        restart.
        """
        self._angles = None

    def release_absolute_yaw(self) -> None:
        """Let the next absolute yaw fix a new offset (the yaw stays continuous then)."""
        self._yaw_offset = None

    def update(
        self,
        wheel_angles: Sequence[float],
        wheel_speeds: Sequence[float],
        absolute_yaw: float | None = None,
    ) -> Pose2D:
        """Move the pose by the wheel angle changes since the previous update.

        Args:
            wheel_angles: one angle per wheel [rad], continuous (multi-turn), wheel order.
            wheel_speeds: one speed per wheel [rad/s], wheel order (for the twist).
            absolute_yaw: chassis yaw from an external reference (IMU) [rad], any offset;
                None for the wheels' turn.

        Returns:
            The new pose (unchanged on the first update: it only sets the reference).

        Raises:
            InputRejectedError: a value is not finite or a count is wrong. The pose is
                left as it was.
        """
        if absolute_yaw is not None and not math.isfinite(absolute_yaw):
            raise InputRejectedError(f'absolute yaw must be finite, got {absolute_yaw!r}')
        twist = self._kinematics.forward(wheel_speeds)
        angles = tuple(float(a) for a in wheel_angles)
        previous = self._angles if self._angles is not None else angles
        if len(angles) != len(previous):
            raise InputRejectedError(f'expected {len(previous)} wheel angles, got {len(angles)}')
        deltas = [a - b for a, b in zip(angles, previous, strict=True)]
        step = self._kinematics.forward(deltas)
        self._angles = angles
        x, y, yaw = self._pose
        if absolute_yaw is None:
            self._source = YawSource.WHEELS
            new_yaw = yaw + step.wz
        else:
            if self._yaw_offset is None:
                # First absolute yaw after none: tie its reference to the current odom yaw.
                self._yaw_offset = absolute_yaw - yaw
            self._source = YawSource.IMU
            # Shortest way from the current (unwrapped) yaw, so the yaw stays continuous.
            new_yaw = yaw + wrap_to_pi(absolute_yaw - self._yaw_offset - yaw)
        dx, dy, _ = body_to_world_twist((step.vx, step.vy, 0.0), 0.5 * (yaw + new_yaw))
        self._pose = Pose2D(x + dx, y + dy, new_yaw)
        self._twist = twist
        return self._pose
