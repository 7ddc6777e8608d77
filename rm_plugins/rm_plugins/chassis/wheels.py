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

The power is predicted at the speeds the wheels will have when an effort has been applied
for a period: the speed feedback is already some milliseconds old and the effort is held
until the next command, and while accelerating hard from low speed the wheels gain tens of
percent of speed in that time (``SpeedPredictor``). Predicting ahead errs on the safe
side whether the wheels speed up (more mechanical power) or brake.

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


class SpeedPredictor:
    """Extrapolates wheel speeds from their last two feedback samples.

    Args:
        max_lead: longest time ahead a speed is extrapolated [s] (and the longest gap
            between samples over which an acceleration is estimated).
    """

    def __init__(self, max_lead: float = 0.05) -> None:
        self._max_lead_ns = round(max_lead * 1e9)
        self.reset()

    def reset(self) -> None:
        """Forget the samples (no acceleration known: predictions are the speeds)."""
        self._stamp_ns: int | None = None
        self._speeds: tuple[float, ...] = ()
        self._accelerations: tuple[float, ...] = ()

    def update(self, stamp_ns: int, speeds: Sequence[float]) -> None:
        """Take the speeds [rad/s] measured at stamp_ns (a repeated stamp is ignored)."""
        speeds = tuple(float(v) for v in speeds)
        last = self._stamp_ns
        if last is not None and stamp_ns == last:
            return
        if last is not None and 0 < stamp_ns - last <= self._max_lead_ns and len(speeds) == len(
            self._speeds
        ):
            span = (stamp_ns - last) / 1e9
            self._accelerations = tuple(
                (new - old) / span for new, old in zip(speeds, self._speeds, strict=True)
            )
        else:
            self._accelerations = (0.0,) * len(speeds)
        self._stamp_ns, self._speeds = stamp_ns, speeds

    def predict(self, at_ns: int) -> tuple[float, ...]:
        """Speeds [rad/s] at at_ns, from the last speeds and accelerations."""
        if self._stamp_ns is None:
            return ()
        lead = min(max(0, at_ns - self._stamp_ns), self._max_lead_ns) / 1e9
        return tuple(v + a * lead for v, a in zip(self._speeds, self._accelerations, strict=True))


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
        power_speeds: Sequence[float] | None = None,
    ) -> WheelEfforts:
        """One step of every wheel loop, then the power limit.

        Args:
            targets: wheel speed targets [rad/s], in wheel order.
            speeds: measured wheel speeds [rad/s], same order.
            dt: time since the previous step [s], finite and > 0 (capped at 50 ms).
            power_limit_w: allowed chassis power [W], >= 0 (inf: no limit).
            power_speeds: the speeds the power is predicted at [rad/s] (e.g. from a
                ``SpeedPredictor``); default the measured speeds.

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
        at = speeds if power_speeds is None else power_speeds
        if len(at) != count:
            raise InputRejectedError(f'need {count} power speeds, got {len(at)}')
        if not all(map(math.isfinite, (*targets, *speeds, *at))):
            raise InputRejectedError(
                f'targets and speeds must be finite: {targets}, {speeds}, {at}'
            )
        dt = min(dt, _MAX_UPDATE_DT)
        efforts = [
            pid.update(target, speed, dt)
            for pid, target, speed in zip(self._pids, targets, speeds, strict=True)
        ]
        result = limit_power(self._model, efforts, at, power_limit_w)
        return WheelEfforts(
            result.torques, result.scale, result.power_w, result.requested_power_w
        )
