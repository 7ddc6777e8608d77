"""Gimbal maths the plugin orchestrates: the per-axis loop, sight-line rates, planar poses.

No ROS here. Angles in rad, REP 103: yaw positive to the left, pitch positive *down*.

The cascade of one axis (``AxisLoop``)::

    world angle target ─► angle PID (on the IMU angle) ─► world rate ─┐
    rate feed-forward ─────────────────────────────────────────────► (+) ─► − base rate
                                                              ─► joint velocity target

The joint velocity target goes to the CAN bridge, whose 1 kHz velocity loop (the motor's
own encoder) turns it into current. The base rate (how fast the body the joint sits on
turns in the world: the chassis for yaw) is measured by the gimbal IMU minus the joint's
own velocity, so the gimbal holds its world heading while the chassis spins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rm_base.control import LowPassFilter, PidConfig, build_pid
from rm_base.geometry import wrap_to_pi


def clamp(value: float, low: float, high: float) -> float:
    """Return value limited to [low, high]."""
    return low if value < low else high if value > high else value


class Smoother:
    """First-order low-pass (``LowPassFilter``) that passes samples through at tau = 0.

    Args:
        tau: time constant [s], >= 0.
        angle: filter an angle: each sample is taken the shortest way round from the
            current value, so the output never jumps at ±pi (it is not wrapped itself).
    """

    def __init__(self, tau: float, *, angle: bool = False) -> None:
        self._filter = LowPassFilter(tau) if tau > 0.0 else None
        self._angle = angle
        self._value: float | None = None

    @property
    def value(self) -> float | None:
        """The output, or None before the first sample."""
        return self._value

    def reset(self, value: float | None = None) -> None:
        """Restart at value, or (None) at the next sample."""
        self._value = value
        if self._filter is not None:
            self._filter.reset(value)

    def update(self, sample: float, dt: float) -> float:
        """Filter one sample taken dt [s] after the previous one; return the output."""
        if self._angle and self._value is not None:
            sample = self._value + wrap_to_pi(sample - self._value)
        if self._filter is None:
            self._value = sample
        else:
            self._value = self._filter.update(sample, dt)
        return self._value


@dataclass(frozen=True)
class AxisOutput:
    """What one axis loop decided in a tick.

    Attributes:
        world_rate: commanded rate in the world frame [rad/s].
        joint_velocity: joint velocity target for the bridge [rad/s].
    """

    world_rate: float
    joint_velocity: float


class AxisLoop:
    """The outer (angle) loop of one axis and the world -> joint velocity conversion.

    Args:
        gains: angle PID (angle mode): error [rad] -> world rate [rad/s]; its
            output_limit also bounds the feed-forward plus PID sum.
        max_joint_velocity: bound of the joint velocity target [rad/s].
    """

    def __init__(self, gains: PidConfig, max_joint_velocity: float) -> None:
        if not gains.angle_mode:
            raise ValueError('a gimbal angle loop needs angle_mode gains')
        self._pid = build_pid(gains)
        self._max_rate = gains.output_limit
        self._max_velocity = max_joint_velocity

    def reset(self) -> None:
        """Forget the integral and the derivative history."""
        self._pid.reset()

    def update(
        self,
        *,
        target: float,
        measured: float,
        rate_feedforward: float,
        base_rate: float,
        dt: float,
        joint_angle: float | None = None,
        joint_limits: tuple[float, float] | None = None,
        limit_gain: float = 0.0,
    ) -> AxisOutput:
        """One tick of the loop.

        Args:
            target: world angle target [rad].
            measured: world angle from the IMU [rad].
            rate_feedforward: expected rate of the target [rad/s].
            base_rate: rate of the joint's base in the world [rad/s].
            dt: time since the previous tick [s], > 0.
            joint_angle: joint angle [rad], for joint_limits.
            joint_limits: (low, high) joint limits [rad]; near them the joint velocity is
                bounded by limit_gain * (distance to the limit), so it never drives past.
            limit_gain: [1/s].

        Returns:
            The world rate and the joint velocity target.
        """
        correction = self._pid.update(target, measured, dt)
        world_rate = clamp(rate_feedforward + correction, -self._max_rate, self._max_rate)
        velocity = world_rate - base_rate
        if joint_limits is not None and joint_angle is not None:
            low, high = joint_limits
            velocity = clamp(
                velocity, limit_gain * (low - joint_angle), limit_gain * (high - joint_angle)
            )
        velocity = clamp(velocity, -self._max_velocity, self._max_velocity)
        return AxisOutput(world_rate, velocity)


def sight_rates(
    offset: tuple[float, float, float], velocity: tuple[float, float, float]
) -> tuple[float, float]:
    """Return how fast the line of sight to a point turns: (yaw rate, pitch rate) [rad/s].

    Args:
        offset: (x, y, z) from the pivot to the point [m], z up.
        velocity: d(offset)/dt [m/s] (minus the pivot's velocity for a fixed point).

    Returns:
        The rate of the bearing atan2(y, x) and of the REP 103 pitch -atan2(z, distance)
        (positive down); (0, 0) at the pivot.
    """
    x, y, z = offset
    vx, vy, vz = velocity
    horizontal2 = x * x + y * y
    if horizontal2 == 0.0:
        return 0.0, 0.0
    distance = math.sqrt(horizontal2)
    yaw_rate = (x * vy - y * vx) / horizontal2
    distance_rate = (x * vx + y * vy) / distance
    pitch_rate = -(distance * vz - z * distance_rate) / (horizontal2 + z * z)
    return yaw_rate, pitch_rate


@dataclass(frozen=True)
class PlanarPose:
    """A pose in the plane of the odometry frame: position [m] and heading [rad]."""

    x: float
    y: float
    yaw: float

    def extrapolated(self, vx: float, vy: float, wz: float, dt: float) -> PlanarPose:
        """Return the pose dt [s] later at a constant body twist (vx, vy [m/s], wz [rad/s]).

        Uses the midpoint heading, as odometry integrates it.
        """
        heading = self.yaw + 0.5 * wz * dt
        c, s = math.cos(heading), math.sin(heading)
        return PlanarPose(
            self.x + (c * vx - s * vy) * dt, self.y + (s * vx + c * vy) * dt, self.yaw + wz * dt
        )

    def to_world(self, x: float, y: float) -> tuple[float, float]:
        """Return a point (x, y) given in this pose's frame in the world frame [m]."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return self.x + c * x - s * y, self.y + s * x + c * y

    def velocity_of(
        self, x: float, y: float, vx: float, vy: float, wz: float
    ) -> tuple[float, float]:
        """Return the world velocity [m/s] of body point (x, y) [m] at body twist (vx, vy, wz)."""
        bx, by = vx - wz * y, vy + wz * x
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return c * bx - s * by, s * bx + c * by
