"""A simulated DR16 receiver on a pseudo-terminal: the operator's DT7 remote.

It sends what the operator holds (:attr:`SimRemote.state`, a DbusFrame: sticks, switches,
dial, and the mouse and keyboard of the PC plugged into the remote) as an 18-byte DBUS
frame every 14 ms, encoded with :mod:`rm_base.hardware.protocols.dbus`, while the remote
is on (:mod:`rm_base.sim.operator_link`). docs/PROTOCOLS.md §5.
"""

from __future__ import annotations

from rm_base.hardware.protocols import dbus
from rm_base.sim.operator_link import OperatorLink


class SimRemote(OperatorLink[dbus.DbusFrame]):
    """The DR16 receiver: centred sticks, both switches middle, nothing pressed at start."""

    def __init__(self, *, path: str, name: str = 'remote') -> None:
        """Open the terminal. Raises: SimConfigError: it cannot be created."""
        super().__init__(dbus.DbusFrame(), 1.0 / dbus.FRAME_PERIOD_S, path=path, name=name)

    def _encode(self, state: dbus.DbusFrame) -> bytes:
        return dbus.encode(state)  # ValueRangeError is a ValueError
