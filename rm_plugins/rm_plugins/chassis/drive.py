"""How the chassis' wheels turn a twist into wheel speeds and back: fixed or steered wheels.

The motion planner asks ``wheel_speeds(twist)`` and the odometry ``forward(speeds)``: fixed
wheels (mecanum, omni) answer with their kinematics as they are (``WheelKinematics``).
Steered wheels (swerve) also need where their modules point: :class:`SwerveDrive` keeps
the steering targets between ticks and the angles measured this tick (``observe``), so
that each module turns at most 90° toward a new direction (the drive flips instead),
wheels that still turn are slowed by the cosine of their steering error, and the odometry
reads the wheels along the directions they really had. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

from rm_base.errors import InputRejectedError
from rm_base.geometry import SwerveKinematics, Twist2D


class Drive(Protocol):
    """What the planner and the odometry need of the wheels."""

    def wheel_speeds(self, twist: Sequence[float]) -> tuple[float, ...]:
        """Wheel speed targets [rad/s] for a chassis twist (vx, vy [m/s], wz [rad/s])."""

    def forward(self, wheel_speeds: Sequence[float]) -> Twist2D:
        """The chassis twist the wheel speeds (or angle changes) give."""


class SwerveDrive:
    """Swerve modules as the planner and the odometry see wheels (module docstring).

    Call :meth:`observe` with the steering joints' angles each tick before the planner or
    the odometry run; :attr:`steer_targets` then holds where the last ``wheel_speeds``
    asked the modules to point.

    Args:
        kinematics: the modules, in the wheel order.
    """

    def __init__(self, kinematics: SwerveKinematics) -> None:
        self.kinematics = kinematics
        self._measured: tuple[float, ...] | None = None
        self._targets: tuple[float, ...] | None = None

    def observe(self, angles: Sequence[float]) -> None:
        """The steering angles measured this tick [rad], unwrapped as the joints count them.

        Raises:
            InputRejectedError: not one finite angle per module.
        """
        measured = tuple(float(a) for a in angles)
        if len(measured) != len(self.kinematics.modules) or not all(
            map(math.isfinite, measured)
        ):
            raise InputRejectedError(
                f'need {len(self.kinematics.modules)} finite steering angles, got {angles!r}'
            )
        self._measured = measured
        if self._targets is None:
            self._targets = measured

    def reset(self) -> None:
        """Forget the steering targets: the next ones start from where the modules point."""
        self._targets = None

    @property
    def steer_targets(self) -> tuple[float, ...]:
        """Where the modules are asked to point [rad] (the measured angles before any ask).

        Raises:
            InputRejectedError: no angles observed yet.
        """
        return self._observed_targets()

    def wheel_speeds(self, twist: Sequence[float]) -> tuple[float, ...]:
        """Wheel speeds for twist; the modules' new steering targets go to steer_targets.

        Raises:
            InputRejectedError: no angles observed yet, or twist not finite.
        """
        states = self.kinematics.module_states(
            twist, self._observed_targets(), measured=self._measured
        )
        self._targets = tuple(s.angle for s in states)
        return tuple(s.speed for s in states)

    def forward(self, wheel_speeds: Sequence[float]) -> Twist2D:
        """The twist of the wheel speeds along the measured module angles.

        Raises:
            InputRejectedError: no angles observed yet, or a speed not finite.
        """
        if self._measured is None:
            raise InputRejectedError('the steering angles have not been observed yet')
        return self.kinematics.forward(self._measured, wheel_speeds)

    def _observed_targets(self) -> tuple[float, ...]:
        if self._targets is None:
            raise InputRejectedError('the steering angles have not been observed yet')
        return self._targets
