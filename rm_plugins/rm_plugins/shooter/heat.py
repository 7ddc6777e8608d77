"""The referee's heat reports for the shooter's barrel model, handed over between threads.

The referee plugin's reports reach the shooter in the thread that delivers them (in
process: the publisher's outbox); the shooter applies them to its ``BarrelHeat`` in its
own tick. 0x0202 heat comes before 0x0207 shots within a tick, which can only count a
shot twice for a moment, never miss one (docs/PROTOCOLS.md §6.5).
"""

from __future__ import annotations

import math
import threading

from rm_msgs.msg import RefereePowerHeat, RefereeRobotStatus, RefereeShot
from rm_plugins.shooter.barrel_heat import BarrelHeat

_NS_PER_S = 1_000_000_000


class RefereeHeatInput:
    """Pending referee reports for one barrel (see the module docstring).

    Args:
        calibre: 17 or 42 [mm]: which heat and which shots are this barrel's.
        timeout_s: no robot status this long: the barrel model falls back to its
            configured limits.
    """

    def __init__(self, calibre: int, timeout_s: float) -> None:
        self._bullet_type = RefereeShot.BULLET_17MM if calibre == 17 else RefereeShot.BULLET_42MM
        self._heat_field = 'heat_17mm' if calibre == 17 else 'heat_42mm'
        self._timeout_ns = round(timeout_s * _NS_PER_S)
        self._lock = threading.Lock()
        self._limits: tuple[float, float] | None = None
        self._limits_ns: int | None = None
        self._heat: float | None = None
        self._shots = 0

    # -- the delivering thread ----------------------------------------------------------------

    def on_robot_status(self, msg: RefereeRobotStatus, receive_ns: int) -> None:
        """The barrel's limit and cooling."""
        with self._lock:
            self._limits = (float(msg.barrel_heat_limit), float(msg.barrel_cooling))
            self._limits_ns = receive_ns

    def on_power_heat(self, msg: RefereePowerHeat, receive_ns: int) -> None:
        """The barrel's heat as the referee counts it."""
        heat = float(getattr(msg, self._heat_field))
        if math.isfinite(heat):
            with self._lock:
                self._heat = heat

    def on_shot(self, msg: RefereeShot, receive_ns: int) -> None:
        """A projectile the referee counted (this barrel's calibre only)."""
        if msg.bullet_type == self._bullet_type:
            with self._lock:
                self._shots += 1

    # -- the shooter's tick ---------------------------------------------------------------------

    def apply(self, heat: BarrelHeat, now_ns: int) -> bool:
        """Hand what arrived to the model; return whether the referee is heard (limits fresh)."""
        with self._lock:
            limits, limits_ns = self._limits, self._limits_ns
            reported, self._heat = self._heat, None
            shots, self._shots = self._shots, 0
        heard = limits is not None and limits_ns is not None and (
            now_ns - limits_ns <= self._timeout_ns
        )
        if heard and limits is not None:
            heat.set_limits(*limits)
        else:
            heat.use_fallback()
        if reported is not None:
            heat.referee_heat(reported)
        for _ in range(shots):
            heat.referee_shot()
        return heard
