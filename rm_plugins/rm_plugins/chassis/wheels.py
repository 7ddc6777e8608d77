"""Wheel speed loops and the power limit: wheel speed targets -> wheel efforts [N·m].

Why the wheel speed PID runs here and not in the bridge: the referee limits the chassis'
electrical power, and the power follows from the torque each motor is asked for (see
``rm_base.control.power_limit``). Only where the torques are computed can they be scaled
before they are sent, which is what RoboMaster firmware does (speed PID per wheel, then
one common factor on the four currents). So each wheel gets a ``rm_base.control.Pid`` from
speed error [rad/s] to effort [N·m], then ``limit_power`` scales the four efforts by one
factor s in [0, 1] so that the predicted power stays under the limit, and the plugin
sends them in MODE_EFFORT. One common factor keeps the direction of the chassis' force and
turn, as desaturation does for speeds.

While the power limit binds, the PIDs' outputs are not what is applied, so their
integrals could wind up; configure ``integral_separation`` (integrate only near the
target, as RoboMaster speed loops do) and a modest ``integral_limit`` to keep the overshoot
small once the limit lets go. No ROS here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

from rm_base.control import ChassisPowerModel, Pid, PidGains, estimate_power, limit_power
from rm_base.errors import InputRejectedError

_MAX_UPDATE_DT = 0.05
"""Longest dt [s] a PID integrates in one step (a stalled tick must not lurch the integral)."""


class WheelEfforts(NamedTuple):
    """One step of the wheel loops.

    Attributes:
        efforts: efforts to send [N·m], in wheel order, after the power limit.
        scale: the power-limit factor s in [0, 1] (1: the limit did not bind).
        power_w: predicted chassis power of the efforts sent [W].
        requested_power_w: predicted power of the PIDs' efforts before scaling [W].
    """

    efforts: tuple[float, ...]
    scale: float
    power_w: float
    requested_power_w: float


class WheelSpeedController:
    """One speed PID per wheel, then the chassis power limit.

    Args:
        count: number of wheels, >= 1.
        gains: PID gains from speed error [rad/s] to effort [N·m]; output_limit is the
            largest effort a wheel is given.
        model: power model of the chassis.
    """

    def __init__(self, count: int, gains: PidGains, model: ChassisPowerModel) -> None:
        if count < 1:
            raise ValueError(f'need at least one wheel, got {count}')
        self._pids = [Pid(gains) for _ in range(count)]
        self._model = model

    @property
    def model(self) -> ChassisPowerModel:
        """The power model."""
        return self._model

    def reset(self) -> None:
        """Forget the PIDs' integrals and history (on enable, disable, PASSIVE)."""
        for pid in self._pids:
            pid.reset()

    def idle_power(self, speeds: Sequence[float]) -> float:
        """Predicted chassis power with no effort at the measured speeds [W]."""
        return estimate_power(self._model, [0.0] * len(speeds), speeds)

    def update(
        self,
        targets: Sequence[float],
        speeds: Sequence[float],
        dt: float,
        power_limit_w: float,
    ) -> WheelEfforts:
        """One step of every wheel loop, then the power limit.

        Args:
            targets: wheel speed targets [rad/s], in wheel order.
            speeds: measured wheel speeds [rad/s], same order.
            dt: time since the previous step [s], finite and > 0 (capped at 50 ms).
            power_limit_w: allowed chassis power [W], >= 0 (inf: no limit).

        Raises:
            InputRejectedError: wrong lengths, a NaN/inf value, dt <= 0, a negative limit.
                The PIDs are left as they were.
        """
        count = len(self._pids)
        if len(targets) != count or len(speeds) != count:
            raise InputRejectedError(
                f'need {count} targets and speeds, got {len(targets)} and {len(speeds)}'
            )
        if not 0.0 < dt < math.inf:
            raise InputRejectedError(f'dt must be finite and > 0 s, got {dt!r}')
        if not power_limit_w >= 0.0:
            raise InputRejectedError(f'power limit must be >= 0 W, got {power_limit_w!r}')
        if not all(math.isfinite(v) for v in (*targets, *speeds)):
            raise InputRejectedError(f'targets and speeds must be finite: {targets}, {speeds}')
        dt = min(dt, _MAX_UPDATE_DT)
        efforts = [
            pid.update(target, speed, dt)
            for pid, target, speed in zip(self._pids, targets, speeds, strict=True)
        ]
        result = limit_power(self._model, efforts, speeds, power_limit_w)
        return WheelEfforts(
            result.torques, result.scale, result.power_w, result.requested_power_w
        )
