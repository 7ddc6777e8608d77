"""From a velocity command to wheel speed targets: ramps, motion mode, kinematics, limits.

One step of :class:`MotionPlanner`:

1. The translation (vx, vy) is ramp-limited **in the frame it is commanded in** (base_link
   in RAW; the gimbal or held-heading frame otherwise). Ramping after the rotation into
   the chassis frame would fight GYRO: at 8 rad/s spin a steady 2 m/s gimbal-frame
   translation turns in the chassis frame at 16 m/s², far above any acceleration limit.
   When the frame changes (RAW <-> FOLLOW, another follow source) the ramp state is
   re-expressed in the new frame, so the chassis keeps its velocity across the switch.
2. ``rm_base.control.ChassisModeController`` turns the ramped translation into the
   chassis-frame twist of the mode (FOLLOW/TWIST PID, GYRO spin, rotation by the yaw
   joint angle); in RAW the commanded wz passes through.
3. wz is ramp-limited (its own axis; spin-up in GYRO, a FOLLOW step). In GYRO the closed
   heading loop (``rm_base.control.SpinHeadingLoop``) then corrects the ramped spin by how
   far the measured heading strays from the one the ramped spin asked for.
4. Inverse kinematics gives the wheel speeds; ``rm_base.geometry.desaturate_speeds`` scales
   them all by one factor k <= 1 so none exceeds the maximum, keeping the direction of motion.
   The ramps' state is scaled by k too, so a command beyond reach does not wind them up
   (releasing it then brakes at once, from the speed actually commanded).

Acceleration limits: each axis has configured launch/normal/brake limits
(``rm_base.control.RampLimits``); a per-command acceleration a > 0 for an axis replaces
its launch and normal limits (speeding up), while braking keeps the configured brake
limit, so a gentle acceleration request never lengthens a stop. No ROS here.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from typing import NamedTuple

from rm_base.control import RampLimiter, RampLimits
from rm_base.errors import InputRejectedError
from rm_base.geometry import (
    Twist2D,
    body_to_world_twist,
    desaturate_speeds,
    world_to_body_twist,
)

from rm_plugins.chassis.drive import Drive
from rm_plugins.chassis.modes import ChassisModeController, ChassisModeParams, ChassisMotionMode
from rm_plugins.chassis.spin_heading import SpinHeadingLoop

_MAX_UPDATE_DT = 0.05
"""Longest dt [s] the ramps and PIDs integrate in one step; a stalled tick (CPU steal) must
not let a ramp jump or a PID integral lurch."""


class FrameKind(enum.Enum):
    """What a translation command is relative to."""

    BASE_LINK = 'base_link'  # the chassis itself (RAW)
    GIMBAL = 'gimbal'  # the gimbal's heading
    HELD = 'held'  # a heading in odom: held since the mode was entered, or odom's own (0)


class CommandFrame(NamedTuple):
    """The frame a translation command is given in.

    Attributes:
        kind: chassis, gimbal, or a held heading.
        heading: the held heading in odom [rad] (HELD only): another heading is another
            frame, so the ramps are re-expressed in it.
    """

    kind: FrameKind
    heading: float | None = None


BASE_LINK_FRAME = CommandFrame(FrameKind.BASE_LINK)
GIMBAL_FRAME = CommandFrame(FrameKind.GIMBAL)
ODOM_FRAME = CommandFrame(FrameKind.HELD, 0.0)


def held_frame(heading: float) -> CommandFrame:
    """The frame of a heading [rad] held in odom."""
    return CommandFrame(FrameKind.HELD, heading)


class MotionOutput(NamedTuple):
    """One step of the planner.

    Attributes:
        twist: chassis-frame twist after ramps and desaturation [m/s, m/s, rad/s].
        wheel_targets: wheel speed targets [rad/s], in wheel order.
        saturation: the desaturation factor k in (0, 1] (1: no wheel at its maximum).
    """

    twist: Twist2D
    wheel_targets: tuple[float, ...]
    saturation: float


def _override(limits: RampLimits, acceleration: float | None) -> RampLimits:
    if acceleration is None:
        return limits
    return RampLimits(
        launch_acceleration=acceleration,
        normal_acceleration=acceleration,
        brake_acceleration=limits.brake_acceleration,
        launch_speed=limits.launch_speed,
    )


class MotionPlanner:
    """Ramps, motion modes, inverse kinematics and desaturation; see the module docstring.

    Args:
        kinematics: the wheels, in wheel-target order.
        mode_params: FOLLOW/TWIST/GYRO parameters.
        linear_limits: default acceleration limits of vx and vy (m/s, m/s²).
        angular_limits: default acceleration limits of wz (rad/s, rad/s²).
        max_wheel_speed: largest |wheel speed| [rad/s], > 0.
    """

    def __init__(
        self,
        kinematics: Drive,
        mode_params: ChassisModeParams,
        linear_limits: RampLimits,
        angular_limits: RampLimits,
        max_wheel_speed: float,
    ) -> None:
        self._kinematics = kinematics
        self._modes = ChassisModeController(mode_params)
        self._spin_heading = SpinHeadingLoop(mode_params.gyro.heading)
        self._defaults = (linear_limits, linear_limits, angular_limits)
        self._max_wheel_speed = max_wheel_speed
        self._accel: tuple[float | None, ...] = (None, None, None)
        self._linear = RampLimiter(self._defaults[:2])
        self._angular = RampLimiter(self._defaults[2:])
        self._frame: CommandFrame | None = None
        self._chassis_linear = (0.0, 0.0)

    @property
    def modes(self) -> ChassisModeController:
        """The motion-mode controller (its target yaw joint angle, for reports)."""
        return self._modes

    @property
    def spin_heading_error(self) -> float:
        """GYRO: the heading loop's last error [rad] (0 outside GYRO)."""
        return self._spin_heading.error

    def reset(self, measured: Twist2D | None = None) -> None:
        """Forget ramps, PIDs and frame; restart the ramps from measured (chassis frame).

        Starting from the measured twist lets a chassis that is still rolling (pushed, or
        coasting after PASSIVE) be taken over smoothly instead of braked to zero first.
        The frame is unknown after a reset, so the first update re-expresses it.
        """
        self._modes.reset()
        self._spin_heading.reset()
        twist = Twist2D() if measured is None else Twist2D(*measured)
        self._chassis_linear = (twist.vx, twist.vy)
        self._linear.reset((0.0, 0.0))
        self._angular.reset((twist.wz,))
        self._frame = None

    def update(
        self,
        mode: ChassisMotionMode,
        frame: CommandFrame,
        command: Sequence[float],
        dt: float,
        *,
        accel: Sequence[float | None] = (None, None, None),
        yaw_joint: float = 0.0,
        yaw_joint_rate: float = 0.0,
        gimbal_yaw_rate: float = 0.0,
        heading: float | None = None,
    ) -> MotionOutput:
        """One control step.

        Args:
            mode: the motion mode.
            frame: the frame the command is in (a change re-expresses the ramp state);
                in RAW BASE_LINK_FRAME, or a held heading (ODOM_FRAME: world-frame speeds).
            command: (vx [m/s], vy [m/s], wz [rad/s]) in that frame; wz is used in RAW only.
            dt: time since the previous step [s], finite and > 0 (capped at 50 ms).
            accel: per-axis acceleration override (vx, vy [m/s²], wz [rad/s²]), None for
                the configured limits.
            yaw_joint: heading of the command frame relative to the chassis [rad]; unused
                in RAW in BASE_LINK_FRAME.
            yaw_joint_rate: its measured rate [rad/s].
            gimbal_yaw_rate: heading rate of the command frame in the world [rad/s], fed
                forward in FOLLOW/TWIST (0 if unknown).
            heading: the chassis' measured heading in odom [rad], for GYRO's heading loop;
                None: the spin runs open loop.

        Returns:
            Twist after the limits, wheel targets and the desaturation factor.

        Raises:
            InputRejectedError: a value is NaN or infinite, or dt <= 0.
        """
        if not 0.0 < dt < math.inf:
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        dt = min(dt, _MAX_UPDATE_DT)
        raw = mode is ChassisMotionMode.RAW
        phi = 0.0 if raw and frame.kind is FrameKind.BASE_LINK else yaw_joint
        if not all(map(math.isfinite, (*command, phi, yaw_joint_rate, gimbal_yaw_rate))):
            raise InputRejectedError(
                f'command, yaw joint angle and rates must be finite, got {tuple(command)}, '
                f'{yaw_joint}, {yaw_joint_rate}, {gimbal_yaw_rate}'
            )
        self._set_accel(tuple(accel))
        if frame != self._frame:
            # Keep the chassis' commanded velocity across the switch: the same vector, now
            # seen in the new frame, which heads phi relative to the chassis.
            self._linear.reset(world_to_body_twist((*self._chassis_linear, 0.0), phi)[:2])
            self._frame = frame
        vx, vy = self._linear.update(command[:2], dt)
        if raw:
            # a world-frame command turns into the chassis frame; its wz is the chassis' own
            cx, cy, _ = body_to_world_twist((vx, vy, 0.0), phi) if phi else (vx, vy, 0.0)
            twist = self._modes.update(mode, (cx, cy, command[2]), 0.0, dt)
        else:
            twist = self._modes.update(
                mode, (vx, vy, 0.0), phi, dt,
                gimbal_yaw_rate=gimbal_yaw_rate, yaw_joint_rate=yaw_joint_rate,
            )
        (wz,) = self._angular.update((twist.wz,), dt)
        turn = wz
        if mode is ChassisMotionMode.GYRO and heading is not None:
            turn = self._spin_heading.update(wz, heading, dt)
        else:
            self._spin_heading.reset()
        targets = self._kinematics.wheel_speeds((twist.vx, twist.vy, turn))
        limited, k = desaturate_speeds(targets, self._max_wheel_speed)
        if k < 1.0:
            self._linear.reset((k * vx, k * vy))
            self._angular.reset((k * wz,))
        out = Twist2D(k * twist.vx, k * twist.vy, k * turn)
        self._chassis_linear = (out.vx, out.vy)
        return MotionOutput(out, limited, k)

    def set_mode_params(self, mode_params: ChassisModeParams) -> None:
        """New FOLLOW/TWIST/GYRO parameters (set while running), from the next update on."""
        self._modes.set_params(mode_params)
        self._spin_heading.set_params(mode_params.gyro.heading)

    def set_default_limits(self, linear_limits: RampLimits, angular_limits: RampLimits) -> None:
        """New default acceleration limits (set while running), from the next update on."""
        self._defaults = (linear_limits, linear_limits, angular_limits)
        accel, self._accel = self._accel, (math.nan,) * 3  # unlike any accel: rebuilt
        self._set_accel(accel)

    def _set_accel(self, accel: tuple[float | None, ...]) -> None:
        if accel == self._accel:
            return
        if len(accel) != 3 or any(a is not None and not 0.0 < a < math.inf for a in accel):
            raise InputRejectedError(f'accel must be 3 of None or finite > 0, got {accel!r}')
        limits = [_override(d, a) for d, a in zip(self._defaults, accel, strict=True)]
        linear, angular = self._linear.values, self._angular.values
        self._linear = RampLimiter(limits[:2])
        self._linear.reset(linear)
        self._angular = RampLimiter(limits[2:])
        self._angular.reset(angular)
        self._accel = accel
