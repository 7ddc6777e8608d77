r"""Bullet-drop compensation: the launch pitch that puts a bullet on a target.

Frame and signs: the shot is in the vertical plane through the muzzle and the target;
``distance`` d >= 0 is horizontal and ``height`` h is up, both from the muzzle [m]. The
answer is a **pitch in the REP 103 sense**, a rotation about +y (y left), under which
**positive pitch turns the barrel down**: aiming up is a negative pitch. ``elevation``
(= -pitch, positive up) is given alongside because that is how the maths reads.

Without drag the elevation theta solves ``h = d tan(theta) - g d² / (2 v² cos²(theta))``,
a quadratic in tan(theta), whose lower root (the flat shot, not the lob) is::

    tan(theta) = (v² - sqrt(v⁴ - g (g d² + 2 h v²))) / (g d)

and no real root (negative discriminant) means the target is out of range. The time of
flight is ``d / (v cos(theta))``.

With drag the bullet decelerates by ``k |v|²`` against its velocity (quadratic drag;
k = rho C_d A / (2 m) [1/m]) and falls with g. There is no closed form, so the trajectory
is integrated with the horizontal distance x as the variable: with slope p = dy/dx and
w = 1 / v_x², the equations

.. math:: y' = p, \quad p' = -g w, \quad w' = 2 k w \sqrt{1 + p^2}, \quad t' = \sqrt{w}

are smooth (RK4 with 16 fixed steps is within 0.1 mm of a fine time-domain integration
over RoboMaster ranges) and end exactly at x = d. Their derivatives with respect to the
launch slope are integrated alongside, so the launch slope is found by Newton's method,
started from the lower root of a closed-form model that flies at least as high (which
also rejects most out-of-range targets without integrating); see
:func:`_solve_with_drag` for why this converges to the lower root. It usually takes 2 or
3 trajectory integrations (about 0.15 ms in CPython).

The model with drag on the horizontal speed only, common in team code
(``x = ln(1 + k vx0 t) / k``, vertical motion drag-free), is not used: it ignores the
drag on the vertical speed, a sizeable fraction of g in a steep shot, and it is not even
a bound (fired downwards, the real bullet falls slower than that model says).

Drag coefficients k, from sphere drag (C_d ≈ 0.47, air 1.2 kg/m³; typical values, not
measurements): 17 mm (3.2 g, 16.8 mm) k ≈ 0.020 1/m; 42 mm (about 44.5 g, 42.5 mm)
k ≈ 0.009 1/m. The 0.038 and 0.019 that circulate as typical team-code values for the
same bullets equal rho C_d A / m, twice this k: check which convention a number was
fitted in before copying it, and better identify k on the range, from the drop of
shots at a few distances.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real
from typing import NamedTuple

from rm_base.errors import ConfigError, InputRejectedError

STANDARD_GRAVITY = 9.80665
"""Standard gravity [m/s²]; use the local value (e.g. 9.79 in much of China) if known."""

_INTEGRATION_STEPS = 16
_MAX_ITERATIONS = 50
_HEIGHT_TOLERANCE_M = 1e-7
# 1 / vx² beyond which a shot counts as spent: below 1 cm/s horizontally.
_MAX_INVERSE_VX2 = 1e4


@dataclass(frozen=True, slots=True)
class ProjectileModel:
    """How a bullet flies.

    Attributes:
        drag: Quadratic drag coefficient k [1/m], >= 0: the bullet decelerates by
            k |v|² against its velocity. 0 disables drag (closed-form solution). See the
            module docstring for typical values.
        gravity: Gravitational acceleration [m/s²], > 0.
    """

    drag: float = 0.0
    gravity: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ('drag', 'gravity'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
                raise ConfigError(f'{owner}.{name} must be a finite number, got {value!r}')
            object.__setattr__(self, name, float(value))
        if self.drag < 0.0:
            raise ConfigError(f'{owner}.drag must be >= 0 1/m, got {self.drag!r}')
        if self.gravity <= 0.0:
            raise ConfigError(f'{owner}.gravity must be > 0 m/s², got {self.gravity!r}')


class BallisticSolution(NamedTuple):
    """A launch angle that hits the target.

    Attributes:
        pitch: REP 103 pitch of the barrel [rad]: positive turns it down, so a shot
            aimed upwards has a negative pitch.
        time_of_flight_s: Time from the muzzle to the target [s].
    """

    pitch: float
    time_of_flight_s: float

    @property
    def elevation(self) -> float:
        """Launch angle above the horizontal [rad] (= -pitch)."""
        return -self.pitch


def _check(distance: float, height: float, speed: float) -> None:
    if not (math.isfinite(distance) and math.isfinite(height) and math.isfinite(speed)):
        raise InputRejectedError(
            f'distance, height and speed must be finite, got {distance!r}, {height!r}, {speed!r}'
        )
    if distance < 0.0:
        raise InputRejectedError(f'distance must be >= 0 m, got {distance!r}')
    if speed <= 0.0:
        raise InputRejectedError(f'bullet speed must be > 0 m/s, got {speed!r}')


def _no_drag_slope(distance: float, height: float, speed: float, gravity: float) -> float | None:
    """Return tan(elevation) of the lower no-drag solution, or None if out of range."""
    v2 = speed * speed
    discriminant = v2 * v2 - gravity * (gravity * distance * distance + 2.0 * height * v2)
    if discriminant < 0.0:
        return None
    # (v² - sqrt(D)) / (g d) rewritten as (g d² + 2 h v²) / (d (v² + sqrt(D))): the same
    # value without the cancellation of v² - sqrt(D) for short, flat shots.
    return (gravity * distance * distance + 2.0 * height * v2) / (
        distance * (v2 + math.sqrt(discriminant))
    )


def _shoot(
    distance: float, slope: float, speed: float, drag: float, gravity: float
) -> tuple[float, float, float] | None:
    """Integrate a shot with launch slope tan(elevation) out to x = distance.

    Returns:
        (height at distance [m], d height / d launch slope [m], time of flight [s]), or
        None if the bullet never gets that far (its horizontal speed is spent first).
    """
    two_k, g = 2.0 * drag, gravity

    def rates(p: float, w: float, dp: float, dw: float) -> tuple[float, ...]:
        """d/dx of (y, p, w, t) and of their derivatives (Y, P, W) by the launch slope."""
        root = math.sqrt(1.0 + p * p)
        return (
            p,
            -g * w,
            two_k * w * root,
            math.sqrt(w),
            dp,
            -g * dw,
            two_k * (dw * root + w * p * dp / root),
        )

    h = distance / _INTEGRATION_STEPS
    half, sixth = 0.5 * h, h / 6.0
    y, p, w, t = 0.0, slope, (1.0 + slope * slope) / (speed * speed), 0.0
    dy, dp, dw = 0.0, 1.0, 2.0 * slope / (speed * speed)
    for _ in range(_INTEGRATION_STEPS):
        k1 = rates(p, w, dp, dw)
        k2 = rates(p + half * k1[1], w + half * k1[2], dp + half * k1[5], dw + half * k1[6])
        k3 = rates(p + half * k2[1], w + half * k2[2], dp + half * k2[5], dw + half * k2[6])
        k4 = rates(p + h * k3[1], w + h * k3[2], dp + h * k3[5], dw + h * k3[6])
        y += sixth * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0])
        p += sixth * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1])
        w += sixth * (k1[2] + 2.0 * (k2[2] + k3[2]) + k4[2])
        t += sixth * (k1[3] + 2.0 * (k2[3] + k3[3]) + k4[3])
        dy += sixth * (k1[4] + 2.0 * (k2[4] + k3[4]) + k4[4])
        dp += sixth * (k1[5] + 2.0 * (k2[5] + k3[5]) + k4[5])
        dw += sixth * (k1[6] + 2.0 * (k2[6] + k3[6]) + k4[6])
        # w = 1 / vx² grows without bound as the horizontal speed is spent.
        if not (w < _MAX_INVERSE_VX2 and math.isfinite(dw) and math.isfinite(dp)):
            return None
    return y, dy, t


def trajectory_height(
    distance: float, pitch: float, speed: float, model: ProjectileModel = ProjectileModel()
) -> tuple[float, float] | None:
    """Return where a shot crosses a horizontal distance: the forward model of the solver.

    Args:
        distance: Horizontal distance from the muzzle [m], >= 0.
        pitch: REP 103 launch pitch [rad], positive down; |pitch| < pi/2.
        speed: Muzzle speed [m/s], > 0.
        model: Drag and gravity.

    Returns:
        (height above the muzzle [m], time of flight [s]) at that distance, or None if
        the shot never gets that far (drag spends its horizontal speed first).

    Raises:
        InputRejectedError: If a value is NaN or infinite, distance < 0, speed <= 0 or
            |pitch| >= pi/2 (a vertical shot has no horizontal distance).
    """
    _check(distance, 0.0, speed)
    if not -0.5 * math.pi < pitch < 0.5 * math.pi:  # also false for NaN
        raise InputRejectedError(f'pitch must be within (-pi/2, pi/2) rad, got {pitch!r}')
    slope = math.tan(-pitch)
    if model.drag == 0.0:
        horizontal_speed = speed * math.cos(pitch)
        height = distance * slope - model.gravity * distance * distance * (1.0 + slope * slope) / (
            2.0 * speed * speed
        )
        return height, distance / horizontal_speed
    shot = _shoot(distance, slope, speed, model.drag, model.gravity)
    if shot is None:
        return None
    height, _, time_s = shot
    return height, time_s


def solve_ballistic(
    distance: float, height: float, speed: float, model: ProjectileModel = ProjectileModel()
) -> BallisticSolution | None:
    """Return the launch pitch (the flat shot, not the lob) that hits a target.

    Args:
        distance: Horizontal distance from the muzzle to the target [m], >= 0.
        height: Height of the target above the muzzle [m]; negative below.
        speed: Muzzle speed [m/s], > 0.
        model: Drag and gravity.

    Returns:
        The REP 103 pitch (negative = up) and time of flight, or None if the target is
        out of range at this speed, or straight above or below the muzzle (distance 0:
        no gimbal aims vertically, and the heading is undefined there).

    Raises:
        InputRejectedError: If a value is NaN or infinite, distance < 0 or speed <= 0.
    """
    _check(distance, height, speed)
    if distance == 0.0:
        return None
    gravity = model.gravity
    if model.drag == 0.0:
        slope = _no_drag_slope(distance, height, speed, gravity)
        if slope is None:
            return None
        elevation = math.atan(slope)
        return BallisticSolution(-elevation, distance / (speed * math.cos(elevation)))
    solved = _solve_with_drag(distance, height, speed, model.drag, gravity)
    if solved is None:
        return None
    slope, time_s = solved
    return BallisticSolution(-math.atan(slope), time_s)


def _bound_slope(
    distance: float, height: float, speed: float, drag: float, gravity: float
) -> float | None:
    """Return the lower root of a closed-form model that flies at least as high as ours.

    In the equations of the module docstring sqrt(1 + p²) >= 1, so w grows at least as
    fast as w0 exp(2 k x), and the slope falls at least as fast as in the model with
    exactly that w, whose height is ``y = s d - (g E / v²)(1 + s²)`` with
    ``E = (exp(2 k d) - 1 - 2 k d) / (4 k²)`` (E = d² / 2 without drag). For every launch
    slope s that model is at least as high at the target, so its lower root is at or left
    of ours, and if it cannot reach the target neither can we. It is the drag-free
    quadratic with d² / 2 replaced by E.
    """
    u = 2.0 * drag * distance
    if u < 1e-3:
        # Series of (e^u - 1 - u) / (u² / 2): the difference cancels for small k d.
        stretched = 0.5 * distance * distance * (1.0 + u / 3.0 + u * u / 12.0)
    else:
        stretched = (math.expm1(u) - u) / (4.0 * drag * drag)
    c = gravity * stretched / (speed * speed)
    # c s² - d s + (c + h) = 0; lower root in the form without cancellation.
    discriminant = distance * distance - 4.0 * c * (c + height)
    if discriminant < 0.0:
        return None
    return 2.0 * (c + height) / (distance + math.sqrt(discriminant))


def _solve_with_drag(
    distance: float, height: float, speed: float, drag: float, gravity: float
) -> tuple[float, float] | None:
    """Return (launch slope, time of flight) of the lower solution, or None if out of range.

    F(s) = (height reached at the target distance) - (target height), as a function of
    the launch slope s = tan(elevation), is concave: exactly so without drag, and checked
    numerically with it (F'' <= -g d² / v² over 5-35 m/s, 0.2-30 m, k up to 0.06 1/m).
    Newton's method on a concave function, from anywhere on its rising side, lands left
    of the lower root after at most one step and then climbs to it monotonically without
    overshooting; and where it finds F < 0 with F' <= 0, no root is left to find. The
    start, from :func:`_bound_slope`, is left of the lower root already.
    """
    slope = _bound_slope(distance, height, speed, drag, gravity)
    if slope is None:
        return None
    for _ in range(_MAX_ITERATIONS):
        shot = _shoot(distance, slope, speed, drag, gravity)
        if shot is None:
            return None  # spent before the target: right of every root
        reached, rate, time_s = shot
        error = reached - height
        if abs(error) <= _HEIGHT_TOLERANCE_M:
            return slope, time_s
        if rate > 0.0:
            slope -= error / rate
        elif error < 0.0:
            return None  # past the peak and still short: out of range
        else:
            # Between the peak and the lob: only rounding in the start can get here.
            # The line of sight is always short and on the rising side; climb from there.
            slope = height / distance
    return None
