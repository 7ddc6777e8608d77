"""The chassis power limit from the referee: its limit, and the buffer energy to spend.

The referee plugin's reports reach the chassis in the thread that delivers them; the
chassis reads the budget in its tick. While the referee is silent (or was never heard) the
chassis keeps its configured default limit, never no limit.
"""

from __future__ import annotations

import math
import threading

from rm_msgs.msg import RefereePowerHeat, RefereeRobotStatus
from rm_plugins.chassis.buffer_energy import BufferEnergyParams, power_budget

_NS_PER_S = 1_000_000_000


class RefereePower:
    """The latest referee limit and buffer energy, and the power they allow.

    Args:
        params: how the buffer is spent and refilled.
        timeout_s: a robot status older than this is no status.
    """

    def __init__(self, params: BufferEnergyParams, timeout_s: float) -> None:
        self._params = params
        self._timeout_ns = round(timeout_s * _NS_PER_S)
        self._lock = threading.Lock()
        self._limit: tuple[float, int] | None = None  # (W, receive ns)
        self._buffer: float | None = None

    def on_robot_status(self, msg: RefereeRobotStatus, receive_ns: int) -> None:
        """The referee's chassis power limit (delivering thread)."""
        limit = float(msg.chassis_power_limit)
        if math.isfinite(limit) and limit >= 0.0:
            with self._lock:
                self._limit = (limit, receive_ns)

    def on_power_heat(self, msg: RefereePowerHeat, receive_ns: int) -> None:
        """The buffer energy (delivering thread)."""
        buffer = float(msg.buffer_energy)
        if math.isfinite(buffer):
            with self._lock:
                self._buffer = buffer

    def heard(self, now_ns: int) -> tuple[float, float]:
        """(the referee's limit [W], buffer [J]) as last heard; NaN for what is not.

        The buffer counts only while the limit is fresh: both come from one referee.
        """
        with self._lock:
            limit, buffer = self._limit, self._buffer
        if limit is None or now_ns - limit[1] > self._timeout_ns:
            return math.nan, math.nan
        return limit[0], math.nan if buffer is None else buffer

    def budget(self, now_ns: int, fallback_w: float) -> float:
        """The power the chassis may draw now [W]; fallback_w while the referee is silent."""
        with self._lock:
            limit, buffer = self._limit, self._buffer
        if limit is None or now_ns - limit[1] > self._timeout_ns:
            return fallback_w
        if buffer is None:  # no buffer reported yet: the limit itself
            return limit[0]
        return power_budget(limit[0], buffer, self._params)
