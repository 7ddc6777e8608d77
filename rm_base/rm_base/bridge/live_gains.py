"""A joint's loop gains set while the bridge runs: ``joints.<joint>.velocity_pid.kp`` ...

The parameters of a positional PID (``kp``, ``ki``, ``kd``, ``output_limit``,
``integral_limit``, ``integral_separation``, ``deadband``, ``derivative_tau_s``) of each
joint's velocity and position loop may change live. :meth:`LiveGains.propose` checks all
the values of one call together (each joint's new gains are built whole, and PidGains
checks them); the loop component applies them at the start of the next tick, before the
actuators update, so a loop never runs with half of a call's gains. The rest of a joint's
table (its bus, id, type, the loops' form) is read at start-up.
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Mapping
from typing import Any

from rm_base.config.schema import InvalidValueError
from rm_base.control import PidGains
from rm_base.control.validation import require_real
from rm_base.errors import ConfigError
from rm_base.hardware.actuators import Actuator
from rm_base.loop.data import JOINT_GAINS

LOOPS = ('velocity_pid', 'position_pid')
#: The fields of a positional PID that may change live.
FIELDS = frozenset(f.name for f in dataclasses.fields(PidGains)) - {'angle_mode'}


class LiveGains:
    """The joints' loop gains, settable between two ticks (a loop component).

    Args:
        actuators: the bridge's actuators by joint.
        loops: each joint's loop configs at start-up, ``{joint: {loop: PidConfig}}``.
    """

    name = 'live gains'
    reads: tuple[str, ...] = ()
    writes = (JOINT_GAINS,)

    def __init__(self, actuators: Mapping[str, Actuator], loops: Mapping[str, Mapping[str, Any]]):
        self._actuators = actuators
        self._gains = {joint: dict(configs) for joint, configs in loops.items()}
        self._pending: dict[str, dict[str, PidGains]] = {}
        self._lock = threading.Lock()

    @staticmethod
    def takes(name: str) -> bool:
        """Whether a parameter name is a joint's loop key (``joints.<joint>.<loop>.<field>``)."""
        parts = name.split('.')
        return len(parts) == 4 and parts[0] == 'joints' and parts[2] in LOOPS

    def propose(self, values: Mapping[str, object]) -> None:
        """Check values (``{parameter name: value}``) and queue them for the next tick.

        Raises:
            InvalidValueError: a key that is not a live one (named, with why), or gains that
                PidGains refuses; nothing of the call is queued.
        """
        with self._lock:
            current = {j: dict(c) for j, c in self._gains.items()}
            for joint, loops in self._pending.items():
                current[joint].update(loops)
        changes: dict[tuple[str, str], dict[str, float]] = {}
        for name, value in values.items():
            _, joint, loop, field = name.split('.')
            if joint not in current:
                raise InvalidValueError(f'{name}: no joint {joint!r}')
            if not isinstance(current[joint].get(loop), PidGains):
                raise InvalidValueError(
                    f'{name}: the {loop} is not a positional PID; its form is read at '
                    'start-up: a change needs a restart'
                )
            if field not in FIELDS:
                raise InvalidValueError(f'{name} is read at start-up: a change needs a restart')
            try:  # a number, not NaN; PidGains checks the rest as at start-up (a limit may
                # be inf: off; a gain may not)
                number = require_real(f'joints.{joint}.{loop}', field, value)
            except ConfigError as err:
                raise InvalidValueError(str(err)) from None
            changes.setdefault((joint, loop), {})[field] = number
        built: dict[str, dict[str, PidGains]] = {}
        for (joint, loop), fields in changes.items():
            try:
                gains = dataclasses.replace(current[joint][loop], **fields)
            except ConfigError as err:
                raise InvalidValueError(f'joints.{joint}.{loop}: {err}') from None
            built.setdefault(joint, {})[loop] = gains
        with self._lock:
            for joint, loops in built.items():
                self._pending.setdefault(joint, {}).update(loops)

    def __call__(self, now_ns: int, dt: float) -> bool:
        """Apply what was queued (the loop's thread, before the actuators' update)."""
        if not self._pending:
            return False
        with self._lock:
            pending, self._pending = self._pending, {}
            for joint, loops in pending.items():
                self._gains[joint].update(loops)
        for joint, loops in pending.items():
            self._actuators[joint].set_loop_gains(
                velocity=loops.get('velocity_pid'), position=loops.get('position_pid')
            )
        return True
