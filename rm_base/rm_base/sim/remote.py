"""A simulated DR16 receiver on a pseudo-terminal: the operator's DT7 remote.

It sends what the operator holds (:attr:`SimRemote.state`: sticks, switches, dial, and
the mouse and keyboard of the PC plugged into the remote) as an 18-byte DBUS frame every
14 ms, encoded with :mod:`rm_base.hardware.protocols.dbus`, while the remote is on. It
starts switched off (a receiver nobody transmits to is silent); :meth:`SimRemote.switch_on`
and :meth:`SimRemote.switch_off` (out of range, flat battery) as the operator does.
docs/PROTOCOLS.md §5.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from rm_base.hardware.errors import ValueRangeError
from rm_base.hardware.protocols import dbus
from rm_base.sim._schedule import RateSchedule
from rm_base.sim.errors import SimConfigError
from rm_base.sim.joint import check_keys
from rm_base.sim.pty_port import PtyPort

_NS_PER_S = 1_000_000_000


class SimRemote:
    """The DR16 receiver (see the module docstring).

    Attributes:
        state: what the operator holds now (a DbusFrame: centred sticks, both switches
            middle, nothing pressed at start).
        on: the remote transmits (False, at start: the receiver is silent).
        port: the simulated serial port the manual-control plugin opens.
    """

    def __init__(self, *, path: str, name: str = 'dr16') -> None:
        """Open the terminal. Raises: SimConfigError: it cannot be created."""
        self.name = name
        self.state = dbus.DbusFrame()
        self.on = False
        self._schedule = RateSchedule(1.0 / dbus.FRAME_PERIOD_S)
        self._frame = dbus.encode(self.state)
        self.port = PtyPort(path, name)

    def hold(self, **fields: Any) -> dbus.DbusFrame:
        """Change what the operator holds (DbusFrame fields: ``channels``, ``switch_a``...).

        Raises:
            SimConfigError: a field the DR16 cannot send (a stick beyond ±660, a switch 0).
        """
        state = dataclasses.replace(self.state, **fields)
        try:
            self._frame = dbus.encode(state)
        except ValueRangeError as err:
            raise SimConfigError(f'{self.name}: {err}') from err
        self.state = state
        return state

    def switch_off(self) -> None:
        """The remote goes silent."""
        self.on = False

    def switch_on(self) -> None:
        """The remote transmits again."""
        self.on = True

    def tick(self, now_ns: int) -> list[bytes]:
        """The frame due at now_ns, if any (called by the world every tick)."""
        if self._schedule.due(now_ns) and self.on:
            return [self._frame]
        return []

    def write(self, frame: bytes) -> None:
        """Write a frame to the terminal."""
        self.port.write(frame)

    def close(self) -> None:
        """Close the terminal (idempotent)."""
        self.port.close()


def remote_from_config(config: Mapping[str, Any]) -> SimRemote:
    """Build the receiver from ``{path, name ('dr16')}`` (the world's ``remote``).

    Raises:
        SimConfigError: a missing path or an unknown key.
    """
    check_keys(config, {'path', 'name'}, 'remote')
    if not isinstance(config.get('path'), str):
        raise SimConfigError(f'remote needs a path (string), got {config.get("path")!r}')
    return SimRemote(path=config['path'], name=str(config.get('name', 'dr16')))
