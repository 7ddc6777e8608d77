"""The super-capacitor controller on the chassis' bus, and the power it lets the chassis draw.

The board (docs/PROTOCOLS.md §8) draws from the referee's chassis output no more than the
limit the robot sends it, charges the capacitor with what the chassis leaves, and gives the
chassis the rest from the capacitor. So with a working capacitor the chassis may draw more
than the referee's limit for a while (a burst), and must draw less for a while to refill it.
:meth:`Supercap.allow` turns the chassis plugin's limit into this tick's allowance:

- offline (no feedback for ``timeout_s``) or faulted (any error bit), and until its
  feedback has been clean for ``fault_clear_s``: the plugin's own limit, unchanged (the
  referee's budget), as if there were no capacitor;
- below ``reserve`` (latched until it is back to ``recharge_to``): the referee's limit less
  ``charge_w``, so that the board refills it;
- asked for more than the referee's limit (a /chassis_cmd ``power_limit`` above it): up to
  ``burst_w`` more, from the capacitor, until it is down to the reserve;
- otherwise the referee's limit, or the lower commanded one.

The power stage of the group the capacitor feeds (``group``, the chassis plugin's name)
calls it every tick with the referee's numbers the plugin handed the stage (a
:class:`PowerSupply`), which this device also sends to the board.
"""

from __future__ import annotations

import dataclasses
import enum
import logging
import math
from collections.abc import Mapping
from typing import Any

import can

from rm_base.config.schema import Schema, declare, keys, number, string
from rm_base.errors import InputRejectedError
from rm_base.hardware.errors import HardwareConfigError
from rm_base.hardware.protocols import supercap as protocol

_log = logging.getLogger(__name__)
_NS_PER_S = 1_000_000_000

@dataclasses.dataclass(frozen=True, kw_only=True)
class SupercapConfig:
    """The ``supercap`` table: the super-capacitor controller (absent: none)."""

    bus: str = declare(string, nonempty=True,
                       description='name of the bus (a key of buses) it is on')
    group: str = declare(string, 'chassis', nonempty=True,
                         description="the power-limit group it feeds: the chassis plugin's name")
    period_s: float = declare(number, 0.01, unit='s', gt=0.0, le=0.1,
                              description="how often the referee's limit and buffer are sent "
                              'to it')
    timeout_s: float = declare(number, 0.05, unit='s', gt=0.0, le=1.0,
                               description='no feedback this long: offline, the referee limit '
                               'alone')
    fault_clear_s: float = declare(number, 0.5, unit='s', ge=0.0, le=60.0,
                                   description='an error or a silence clears after this long '
                                   'of clean feedback')
    reserve: float = declare(number, 0.3, ge=0.0, le=1.0,
                             description='energy kept (a fraction of full): a burst stops at '
                             'it; below it the chassis draws less until the capacitor is back '
                             'to recharge_to')
    recharge_to: float = declare(number, 0.5, ge=0.0, le=1.0,
                                 description='energy (a fraction of full) to refill to once '
                                 'below the reserve')
    charge_w: float = declare(number, 15.0, unit='W', ge=0.0,
                              description='how far under the referee limit the chassis stays '
                              'while refilling')
    burst_w: float = declare(number, 100.0, unit='W', ge=0.0,
                             description='most power a burst takes from the capacitor beyond '
                             'the referee limit')

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> SupercapConfig:
        """Parse ``supercap``.

        Raises:
            HardwareConfigError: a missing, unknown or invalid key.
        """
        values = SUPERCAP_SCHEMA.read('supercap', data, HardwareConfigError)
        if values['recharge_to'] < values['reserve']:
            raise HardwareConfigError('supercap.recharge_to must be >= supercap.reserve')
        return cls(**values)


#: ``supercap``'s keys as a table reader (and the parameter reference's rows)
SUPERCAP_SCHEMA = Schema(tuple(key for _, key in keys(SupercapConfig)))


@dataclasses.dataclass(frozen=True)
class PowerSupply:
    """What the chassis knows of its power, for the capacitor.

    Attributes:
        referee_limit_w: the referee's chassis power limit [W]; NaN: not heard.
        buffer_j: the referee's buffer energy [J]; NaN: not heard.
        request_w: a commanded limit [W] (0: none); above the referee's, a burst.
    """

    referee_limit_w: float = math.nan
    buffer_j: float = math.nan
    request_w: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.request_w) and self.request_w >= 0.0):
            raise InputRejectedError(f'power request {self.request_w!r} W: finite, >= 0')
        limit = self.referee_limit_w
        if not (math.isnan(limit) or (math.isfinite(limit) and limit >= 0.0)):
            raise InputRejectedError(f'referee limit {limit!r} W: NaN (unknown) or >= 0')
        if math.isinf(self.buffer_j):
            raise InputRejectedError(f'buffer {self.buffer_j!r} J: NaN (unknown) or finite')


class CapState(enum.Enum):
    """What the capacitor does for the chassis now."""

    OFFLINE = 'offline'  # no feedback (never, or not for timeout_s)
    FAULT = 'fault'  # an error bit, or not yet clean for fault_clear_s
    CHARGING = 'charging'  # below the reserve: refilling to recharge_to
    READY = 'ready'  # usable; the chassis draws the referee's limit
    BURST = 'burst'  # the chassis draws beyond the referee's limit, from the capacitor


class Supercap:
    """The controller on one bus (see the module docstring).

    Args:
        config: the ``supercap`` table.
        rate_hz: the loop's rate (the command goes out every ``period_s`` of ticks).
    """

    def __init__(self, config: SupercapConfig, rate_hz: float) -> None:
        self.config = config
        self.bus_name = config.bus
        self.supply = PowerSupply()
        #: The plugin's limit of the last tick [W] (sent while the referee is not heard).
        self.fallback_w = math.inf
        self.frames_decoded = 0
        self.decode_errors = 0
        self._every = max(1, round(config.period_s * rate_hz))
        self._ticks = 0
        self._timeout_ns = round(config.timeout_s * _NS_PER_S)
        self._clear_ns = round(config.fault_clear_s * _NS_PER_S)
        self._feedback: protocol.CapFeedback | None = None
        self._last_ns: int | None = None
        self._clean_since_ns: int | None = None  # first frame of the clean run
        self._charging = False
        self._bursting = False

    # -- the loop ------------------------------------------------------------------------

    def feedback_ids(self) -> tuple[int, ...]:
        """The ids of the frames it reads."""
        return (protocol.FEEDBACK_ID,)

    def handle_frame(self, msg: can.Message, now_ns: int) -> bool:
        """Take a 0x051 frame (the bus's receive path); True if it was the board's."""
        if msg.arbitration_id != protocol.FEEDBACK_ID or msg.is_extended_id:
            return False
        try:
            feedback = protocol.decode_feedback(bytes(msg.data))
        except InputRejectedError as err:
            self.decode_errors += 1
            if self.decode_errors == 1 or self.decode_errors % 1000 == 0:
                _log.warning('supercap: bad frame 0x%03X (%d so far): %s',
                             msg.arbitration_id, self.decode_errors, err)
            return True
        self.frames_decoded += 1
        silent = self._last_ns is None or now_ns - self._last_ns > self._timeout_ns
        if feedback.errors or silent:
            # an error, or the first frame after a silence: evidence starts again
            self._clean_since_ns = None if feedback.errors else now_ns
        elif self._clean_since_ns is None:
            self._clean_since_ns = now_ns
        self._feedback, self._last_ns = feedback, now_ns
        if feedback.energy < self.config.reserve:
            self._charging = True
        elif feedback.energy >= self.config.recharge_to:
            self._charging = False
        return True

    def pack_command(self) -> can.Message | None:
        """The 0x061 frame every ``period_s``: the referee's limit and buffer."""
        self._ticks += 1
        if self._ticks < self._every:
            return None
        self._ticks = 0
        supply = self.supply
        limit = supply.referee_limit_w
        if math.isnan(limit):  # the referee unheard: the plugin's own limit
            limit = self.fallback_w if math.isfinite(self.fallback_w) else protocol.MIN_LIMIT_W
        buffer = 0.0 if math.isnan(supply.buffer_j) else supply.buffer_j  # unknown: empty
        return can.Message(arbitration_id=protocol.COMMAND_ID, is_extended_id=False,
                           data=protocol.encode_command(limit, buffer))

    def state(self, now_ns: int) -> CapState:
        """What it does for the chassis now."""
        if self._last_ns is None or now_ns - self._last_ns > self._timeout_ns:
            return CapState.OFFLINE
        since = self._clean_since_ns
        if since is None or now_ns - since < self._clear_ns:
            return CapState.FAULT
        if self._charging:
            return CapState.CHARGING
        return CapState.BURST if self._bursting else CapState.READY

    def allow(self, limit_w: float, supply: PowerSupply, now_ns: int) -> float:
        """The power the chassis may draw this tick [W], given the plugin's limit_w."""
        self.fallback_w, self.supply = limit_w, supply
        state = self.state(now_ns)
        self._bursting = False
        if state in (CapState.OFFLINE, CapState.FAULT):
            return limit_w
        base = supply.referee_limit_w
        if math.isnan(base):
            base = limit_w
        if state is CapState.CHARGING:
            return max(0.0, base - self.config.charge_w)
        request = supply.request_w
        if request > base:
            self._bursting = True
            return min(request, base + self.config.burst_w)
        return request if request > 0.0 else base

    # -- reports -------------------------------------------------------------------------

    def report(self, now_ns: int) -> dict[str, Any]:
        """Its state and last feedback, for /diagnostics and the status line."""
        fb = self._feedback
        return {
            'bus': self.bus_name,
            'state': self.state(now_ns).value,
            'energy': fb.energy if fb is not None else math.nan,
            'chassis_power_w': fb.chassis_power_w if fb is not None else math.nan,
            'board_limit_w': fb.limit_w if fb is not None else 0,
            'errors': ', '.join(e.name.lower().replace('_', ' ') for e in fb.errors
                                if e.name) if fb is not None else '',
            'referee_limit_w': self.supply.referee_limit_w,
            'request_w': self.supply.request_w,
            'frames_decoded': self.frames_decoded,
            'decode_errors': self.decode_errors,
        }


def check_bus(config: SupercapConfig, bus_names: set[str]) -> None:
    """Refuse a supercap on a bus that is not configured."""
    if config.bus not in bus_names:
        raise HardwareConfigError(
            f'supercap.bus {config.bus!r} is not a configured bus {sorted(bus_names)}')
