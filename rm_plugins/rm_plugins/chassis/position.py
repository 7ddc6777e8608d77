"""POSITION mode: move by (dx, dy, dyaw) from where a move starts, then stop and hold.

The goal is fixed in odom when a move starts: ``dx, dy`` along base_link's axes at that
moment, the heading turned by ``dyaw``. Each run the remaining offset asks for a velocity
toward the goal (in odom; the chassis' ramps then limit its acceleration), per axis the
least of

- the axis' top speed (``max_speed``, ``max_rate``),
- the speed from which the braking acceleration stops it at the goal: ``sqrt(2 a d)``,
- ``gain * d``, so that the last centimetres close smoothly instead of chattering.

The move has arrived when both the distance and the heading error are within their
tolerances; the same law then holds the pose. No ROS here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rm_base.geometry import wrap_to_pi


@dataclass(frozen=True)
class PositionConfig:
    """How POSITION moves (``chassis.position.*``).

    Attributes:
        max_speed: top translation speed [m/s].
        max_rate: top turn rate [rad/s].
        gain: speed per unit of remaining offset near the goal [1/s].
        tolerance: arrived within this distance [m].
        yaw_tolerance: and within this heading error [rad].
    """

    max_speed: float
    max_rate: float
    gain: float
    tolerance: float
    yaw_tolerance: float


#: The defaults of ``chassis.position.*``.
DEFAULT_POSITION = PositionConfig(
    max_speed=1.5, max_rate=3.0, gain=4.0, tolerance=0.02, yaw_tolerance=0.02
)


@dataclass(frozen=True)
class Goal:
    """A move's goal in odom: position [m] and heading [rad]."""

    x: float
    y: float
    yaw: float


def goal_of(x: float, y: float, yaw: float, move: tuple[float, float, float]) -> Goal:
    """The goal of move (dx, dy along the robot's axes, dyaw) from the pose (x, y, yaw)."""
    dx, dy, dyaw = move
    c, s = math.cos(yaw), math.sin(yaw)
    return Goal(x + c * dx - s * dy, y + s * dx + c * dy, wrap_to_pi(yaw + dyaw))


def approach_speed(distance: float, top: float, brake: float | None, gain: float) -> float:
    """Speed toward a goal distance away (>= 0): see the module docstring.

    brake: the braking acceleration [u/s²]; None: unlimited (the gain alone slows it).
    """
    speed = min(top, gain * distance)
    if brake is not None:
        speed = min(speed, math.sqrt(2.0 * brake * distance))
    return speed


def position_command(
    pose: tuple[float, float, float],
    goal: Goal,
    cfg: PositionConfig,
    brake: tuple[float | None, float | None],
) -> tuple[tuple[float, float, float], bool]:
    """The velocity toward goal, and whether the robot has arrived.

    Args:
        pose: the robot's (x [m], y [m], yaw [rad]) in odom.
        goal: the move's goal in odom.
        cfg: speeds, gain and tolerances.
        brake: braking acceleration of translation [m/s²] and rotation [rad/s²] (None:
            unlimited).

    Returns:
        ((vx, vy) in odom [m/s], wz [rad/s]) and arrived.
    """
    x, y, yaw = pose
    ex, ey = goal.x - x, goal.y - y
    eyaw = wrap_to_pi(goal.yaw - yaw)
    distance = math.hypot(ex, ey)
    speed = approach_speed(distance, cfg.max_speed, brake[0], cfg.gain)
    vx, vy = (speed * ex / distance, speed * ey / distance) if distance > 0.0 else (0.0, 0.0)
    wz = math.copysign(approach_speed(abs(eyaw), cfg.max_rate, brake[1], cfg.gain), eyaw)
    arrived = distance <= cfg.tolerance and abs(eyaw) <= cfg.yaw_tolerance
    return (vx, vy, wz), arrived
