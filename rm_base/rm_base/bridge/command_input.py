"""The bridge's /actuator_cmd input: each message applied to the hardware whole, or refused.

The rules are :mod:`rm_base.bridge.commands` (well-formed, fresh, computed from this
bridge's states); this module applies them to each message, sets the targets of one that
passes, and counts both kinds for /diagnostics. No rclpy: the node hands in its clock and
logger.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Collection
from typing import Any, Protocol

from rm_base.bridge.commands import (
    ActuatorCmdLike,
    check_stamp,
    check_states_stamp,
    first_states_stamp,
    parse_actuator_cmd,
)
from rm_base.bridge.diagnostics import CommandStats
from rm_base.bridge.errors import ActuatorCmdRejectedError
from rm_base.joints import JointTarget


class TargetSink(Protocol):
    """Where targets go: ``CanHardware.set_target``."""

    def set_target(self, name: str, target: JointTarget, *, age_ns: int = 0) -> None:
        """Set one joint's target, already checked, ``age_ns`` after its stamp."""


class ActuatorCmdInput:
    """Applies /actuator_cmd messages (the inbox's or the executor's thread) and counts them.

    Args:
        hardware: takes the targets of a message that passes.
        joints: the joints this bridge drives.
        timeout_s: safety.command_timeout_s [s].
        now_ns: the bridge's clock [ns], the one its states are stamped with.
        warn: says why a message was refused (the caller throttles it).
    """

    def __init__(
        self,
        hardware: TargetSink,
        joints: Collection[str],
        timeout_s: float,
        now_ns: Callable[[], int],
        warn: Callable[[str], Any],
    ) -> None:
        self._hardware = hardware
        self._joints = frozenset(joints)
        self._timeout_s = timeout_s
        self._now_ns = now_ns
        self._warn = warn
        self._lock = threading.Lock()
        self._accepted = 0
        self._rejected: dict[str, int] = {}
        self._last_rejection: str | None = None
        self._first_states_ns: int | None = None

    def states_published(self, stamp_ns: int) -> None:
        """Note states stamped stamp_ns, before they go out (a reply may come at once)."""
        self._first_states_ns = first_states_stamp(self._first_states_ns, stamp_ns)

    def __call__(self, msg: ActuatorCmdLike) -> None:
        """Apply msg whole, or refuse it whole (counted, and said through ``warn``)."""
        try:
            age_ns = check_stamp(msg, self._now_ns(), self._timeout_s)
            check_states_stamp(msg, self._first_states_ns)
            # checked whole here (every joint is this bridge's): applied without a second look
            for name, target in parse_actuator_cmd(msg, self._joints):
                self._hardware.set_target(name, target, age_ns=age_ns)
        except ActuatorCmdRejectedError as err:
            reason = err.reason.value
            with self._lock:
                count = self._rejected.get(reason, 0) + 1
                self._rejected[reason] = count
                self._last_rejection = f'{reason}: {err}'
            self._warn(f'rejected /actuator_cmd ({reason}, {count} so far): {err}')
            return
        with self._lock:
            self._accepted += 1

    def stats(self) -> CommandStats:
        """The counters, read together."""
        with self._lock:
            return CommandStats(self._accepted, dict(self._rejected), self._last_rejection)
