"""Chassis electrical power model and the referee power limit.

The referee measures the electrical power the chassis draws and punishes a robot that
stays above its limit. The wheel controllers ask for torques; this module predicts the
power those torques will draw and, when it is too much, scales all of them by one factor
s in [0, 1] (one factor keeps the direction of the chassis force and turn, as
:func:`rm_base.geometry.desaturate` does for speeds).

The model, per wheel motor i with output-shaft torque tau_i [N·m] (the command about to be
sent) and output-shaft speed w_i [rad/s] (measured)::

    P = sum_i (tau_i * w_i + k1 * tau_i**2 + k2 * w_i**2) + P_static

- ``tau * w`` is the mechanical power; negative while a wheel brakes (regeneration).
- ``k1 * tau**2`` is the copper loss (current squared times winding resistance, with
  current proportional to torque): k1 = (3/2) R_phase / Kt² for a three-phase motor.
- ``k2 * w**2`` lumps the losses that grow with speed (iron, friction, ESC switching).
- ``P_static`` is what the chassis power rail draws with the wheels at rest (ESCs idle).

Typical values for an M3508 with a C620 ESC, output-shaft units (19.2:1 gearbox):
k1 ≈ 2.96 W/(N·m)², k2 ≈ 3.08e-3 W/(rad/s)², about 0.7 W static per motor. These are the
values used by Alliance-Algorithm/RMCS (rmcs_core, steering_wheel/motor.hpp); the datasheet
agrees on k1: (3/2) * 0.194 Ω / (0.3 N·m/A)² ≈ 3.2 W/(N·m)². Identify them on your own
robot: record the commanded torques, measured wheel speeds and the referee's chassis power
(or a power meter on the chassis rail) while driving, spinning and braking at many speeds,
then fit with :func:`fit_power_model`.

Scaling: with every torque multiplied by s the prediction is quadratic in s::

    P(s) = (k1 * sum tau²) s² + (sum tau * w) s + (k2 * sum w² + P_static)

and :func:`power_limit_scale` returns the largest s in [0, 1] with P(s) <= P_limit:

- s = 1 when the request is already within the limit (also when it is regenerating:
  a negative ``sum tau * w`` is never scaled up, s never exceeds 1), or when there is
  nothing to scale (all torques zero).
- s = 0 when the limit is below the static power: no torque can be afforded.
- Otherwise the larger root of P(s) = P_limit when it lies in [0, 1].
- When no s in [0, 1] meets the limit (the speed losses alone exceed it), the s that
  draws the least power: 0 while the wheels drive, and while they brake the amount of
  braking that lowers the power most, since braking also sheds the speed losses.
"""

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from rm_base.control.validation import require_non_negative
from rm_base.errors import InputRejectedError


@dataclass(frozen=True, slots=True)
class ChassisPowerModel:
    """Coefficients of the chassis power model; see the module docstring.

    Attributes:
        k1: Copper-loss coefficient per wheel motor [W/(N·m)²], >= 0 (M3508 ≈ 2.96).
        k2: Speed-loss coefficient per wheel motor [W/(rad/s)²], >= 0 (M3508 ≈ 3.08e-3).
        static_power_w: Power of the whole chassis rail with the wheels at rest [W], >= 0
            (about 0.7 W per M3508 plus whatever else hangs on that rail).
    """

    k1: float
    k2: float
    static_power_w: float = 0.0

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ('k1', 'k2', 'static_power_w'):
            object.__setattr__(self, name, require_non_negative(owner, name, getattr(self, name)))


class PowerLimitResult(NamedTuple):
    """What :func:`limit_power` did.

    Attributes:
        scale: The common factor s in [0, 1] applied to every torque.
        torques: The scaled torques [N·m], in wheel order.
        requested_power_w: Predicted power of the torques as asked [W].
        power_w: Predicted power of the scaled torques [W].
    """

    scale: float
    torques: tuple[float, ...]
    requested_power_w: float
    power_w: float


def _sums(torques: Sequence[float], speeds: Sequence[float]) -> tuple[float, float, float]:
    """Return (sum tau², sum tau * w, sum w²) after checking the inputs."""
    if len(torques) != len(speeds):
        raise InputRejectedError(
            f'need one speed per torque, got {len(torques)} torques and {len(speeds)} speeds'
        )
    tau_tau = tau_w = w_w = 0.0
    for tau, w in zip(torques, speeds, strict=True):
        if not (math.isfinite(tau) and math.isfinite(w)):
            raise InputRejectedError(
                f'torques and speeds must be finite, got {torques!r}, {speeds!r}'
            )
        tau_tau += tau * tau
        tau_w += tau * w
        w_w += w * w
    return tau_tau, tau_w, w_w


def _check_limit(power_limit_w: float) -> None:
    if not power_limit_w >= 0.0:  # also true for NaN
        raise InputRejectedError(f'power limit must be >= 0 W, got {power_limit_w!r}')


def estimate_power(
    model: ChassisPowerModel, torques: Sequence[float], speeds: Sequence[float]
) -> float:
    """Return the predicted electrical power of the chassis [W].

    Args:
        model: Power model coefficients.
        torques: Output-shaft torque of each wheel motor [N·m].
        speeds: Output-shaft speed of each wheel motor [rad/s], same order.

    Raises:
        InputRejectedError: If the lengths differ or a value is NaN or infinite.
    """
    return _power(model, _sums(torques, speeds))


def _power(model: ChassisPowerModel, sums: tuple[float, float, float]) -> float:
    tau_tau, tau_w, w_w = sums
    return model.k1 * tau_tau + tau_w + model.k2 * w_w + model.static_power_w


def power_limit_scale(
    model: ChassisPowerModel,
    torques: Sequence[float],
    speeds: Sequence[float],
    power_limit_w: float,
) -> float:
    """Return the largest common torque factor s in [0, 1] that keeps P(s) <= power_limit_w.

    See the module docstring for the cases where no such s exists.

    Args:
        model: Power model coefficients.
        torques: Requested output-shaft torque of each wheel motor [N·m].
        speeds: Measured output-shaft speed of each wheel motor [rad/s], same order.
        power_limit_w: Allowed chassis power [W], >= 0 (inf: no limit).

    Returns:
        The factor s in [0, 1].

    Raises:
        InputRejectedError: If the lengths differ, a value is NaN or infinite, or the
            limit is negative or NaN.
    """
    return _scale(model, _sums(torques, speeds), power_limit_w)


def _scale(
    model: ChassisPowerModel, sums: tuple[float, float, float], power_limit_w: float
) -> float:
    """``power_limit_scale`` from the sums of ``_sums``."""
    tau_tau, tau_w, w_w = sums
    _check_limit(power_limit_w)
    if tau_tau == 0.0:
        return 1.0  # nothing to scale
    if power_limit_w < model.static_power_w:
        return 0.0
    # q(s) = P(s) - P_limit = a s² + b s + c; find the largest s in [0, 1] with q(s) <= 0.
    a = model.k1 * tau_tau
    b = tau_w
    c = model.k2 * w_w + model.static_power_w - power_limit_w
    if a + b + c <= 0.0:
        return 1.0
    # From here q(1) > 0: the limit binds.
    if a > 0.0:
        discriminant = b * b - 4.0 * a * c
        if discriminant >= 0.0:
            root = math.sqrt(discriminant)
            # Larger root of q, in the form that does not cancel for either sign of b.
            if b < 0.0:
                upper = (-b + root) / (2.0 * a)
            else:
                denominator = -b - root
                upper = 2.0 * c / denominator if denominator < 0.0 else 0.0
            # q(1) > 0 and q is convex, so [0, 1] meets q <= 0 only left of 1, ending at
            # the larger root; both roots above 1 (upper > 1) means it does not meet it.
            if 0.0 <= upper <= 1.0:
                return upper
        # Infeasible: the least power is at the vertex (b < 0, braking) or at 0.
        return min(1.0, max(0.0, -b / (2.0 * a)))
    # k1 = 0: q is linear in s.
    if b > 0.0:
        return max(0.0, -c / b)  # -c / b < 1 because q(1) = b + c > 0
    # b <= 0: q(s) >= q(1) > 0 everywhere; braking (b < 0) is cheapest at full torque.
    return 1.0 if b < 0.0 else 0.0


def limit_power(
    model: ChassisPowerModel,
    torques: Sequence[float],
    speeds: Sequence[float],
    power_limit_w: float,
) -> PowerLimitResult:
    """Scale the wheel torques by :func:`power_limit_scale` and report the powers.

    Args:
        model: Power model coefficients.
        torques: Requested output-shaft torque of each wheel motor [N·m].
        speeds: Measured output-shaft speed of each wheel motor [rad/s], same order.
        power_limit_w: Allowed chassis power [W], >= 0 (inf: no limit).

    Returns:
        The factor, the scaled torques and the predicted power before and after.

    Raises:
        InputRejectedError: As :func:`power_limit_scale`.
    """
    sums = _sums(torques, speeds)  # once for the scale and the requested power
    scale = _scale(model, sums, power_limit_w)
    scaled = tuple(scale * tau for tau in torques)
    return PowerLimitResult(
        scale=scale,
        torques=scaled,
        requested_power_w=_power(model, sums),
        power_w=estimate_power(model, scaled, speeds),
    )


def fit_power_model(
    torques: ArrayLike, speeds: ArrayLike, measured_power_w: ArrayLike
) -> ChassisPowerModel:
    """Identify the model coefficients from logged samples by least squares.

    Fits ``P - sum tau * w = k1 * sum tau² + k2 * sum w² + P_static`` over the samples.
    Log at a steady rate while the chassis accelerates, cruises, spins and brakes across
    its speed range, so that torque and speed vary independently; a few thousand samples
    are plenty. Align the logs first: the referee reports power at 10-50 Hz and late.

    Args:
        torques: Commanded output-shaft torques, shape (M samples, N wheels) [N·m].
        speeds: Measured output-shaft speeds, shape (M, N) [rad/s].
        measured_power_w: Measured chassis power, shape (M,) [W].

    Returns:
        The fitted coefficients.

    Raises:
        InputRejectedError: If the shapes disagree, a value is not finite, the samples do
            not separate the three terms (too few, or torque and speed never vary), or
            the fit gives a negative coefficient (a sign that the logs are misaligned or
            the power meter has an offset).
    """
    tau = np.asarray(torques, dtype=float)
    w = np.asarray(speeds, dtype=float)
    power = np.asarray(measured_power_w, dtype=float)
    if tau.ndim != 2 or tau.shape != w.shape or power.shape != tau.shape[:1]:
        raise InputRejectedError(
            'need torques and speeds of shape (M, N) and power of shape (M,), got '
            f'{tau.shape}, {w.shape}, {power.shape}'
        )
    if not (np.all(np.isfinite(tau)) and np.all(np.isfinite(w)) and np.all(np.isfinite(power))):
        raise InputRejectedError('power-model samples must be finite')
    regressors = np.column_stack(
        [np.sum(tau * tau, axis=1), np.sum(w * w, axis=1), np.ones(len(power))]
    )
    if np.linalg.matrix_rank(regressors) < 3:
        raise InputRejectedError(
            'the samples do not separate k1, k2 and the static power: log more, with '
            'torque and speed varying independently'
        )
    residual_power = power - np.sum(tau * w, axis=1)
    (k1, k2, static), *_ = np.linalg.lstsq(regressors, residual_power, rcond=None)
    if min(k1, k2, static) < 0.0:
        raise InputRejectedError(
            f'fit gave a negative coefficient (k1={k1:.4g}, k2={k2:.4g}, '
            f'static={static:.4g} W): check the log alignment and the power meter offset'
        )
    return ChassisPowerModel(k1=float(k1), k2=float(k2), static_power_w=float(static))
