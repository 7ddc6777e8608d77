"""A simulated image link on a pseudo-terminal: the operator's keyboard and mouse.

The client PC's keyboard and mouse reach the robot through the image-transmission module's
UART as 0x0304 frames (30 Hz; docs/PROTOCOLS.md §6), built with
:mod:`rm_base.hardware.protocols.referee`. It starts silent (no client connected);
:meth:`SimImageLink.connect` and :meth:`SimImageLink.disconnect` as the operator's client
does, :meth:`SimImageLink.hold` sets what is pressed and how the mouse moves.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from rm_base.hardware.protocols import referee as ref
from rm_base.sim._schedule import RateSchedule
from rm_base.sim.errors import SimConfigError
from rm_base.sim.joint import check_keys
from rm_base.sim.pty_port import PtyPort

#: 0x0304 frames per second.
RATE_HZ = 30.0


class SimImageLink:
    """The image link's keyboard-and-mouse stream (see the module docstring).

    Attributes:
        state: what the operator does now (a KeyboardMouse record).
        connected: the client sends (False, at start: silent).
        port: the simulated serial port the manual-control plugin opens.
    """

    def __init__(self, *, path: str, name: str = 'image_link') -> None:
        """Open the terminal. Raises: SimConfigError: it cannot be created."""
        self.name = name
        self.state = ref.KeyboardMouse(0, 0, 0, False, False, 0)
        self.connected = False
        self._schedule = RateSchedule(RATE_HZ)
        self._seq = 0
        self.port = PtyPort(path, name)

    def hold(self, **fields: Any) -> ref.KeyboardMouse:
        """Change what the operator does (KeyboardMouse fields: ``mouse_x``, ``keys``...).

        Raises:
            SimConfigError: a value the frame cannot carry.
        """
        state = dataclasses.replace(self.state, **fields)
        try:
            ref.encode_status(state, ref.ProtocolVersion.V2025)
        except ValueError as err:
            raise SimConfigError(f'{self.name}: {err}') from err
        self.state = state
        return state

    def connect(self) -> None:
        """The client starts sending."""
        self.connected = True

    def disconnect(self) -> None:
        """The client goes silent."""
        self.connected = False

    def tick(self, now_ns: int) -> list[bytes]:
        """The frame due at now_ns, if any (called by the world every tick)."""
        if not (self._schedule.due(now_ns) and self.connected):
            return []
        cmd_id, data = ref.encode_status(self.state, ref.ProtocolVersion.V2025)
        frame = ref.encode_frame(cmd_id, data, seq=self._seq)
        self._seq = (self._seq + 1) & 0xFF
        return [frame]

    def write(self, frame: bytes) -> None:
        """Write a frame to the terminal."""
        self.port.write(frame)

    def close(self) -> None:
        """Close the terminal (idempotent)."""
        self.port.close()


def image_link_from_config(config: Mapping[str, Any]) -> SimImageLink:
    """Build the link from ``{path, name ('image_link')}`` (the world's ``image_link``).

    Raises:
        SimConfigError: a missing path or an unknown key.
    """
    check_keys(config, {'path', 'name'}, 'image_link')
    if not isinstance(config.get('path'), str):
        raise SimConfigError(f'image_link needs a path (string), got {config.get("path")!r}')
    return SimImageLink(path=config['path'], name=str(config.get('name', 'image_link')))
