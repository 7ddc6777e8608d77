"""A simulated image link on a pseudo-terminal: the operator's keyboard and mouse.

The client PC's keyboard and mouse reach the robot through the image-transmission module's
UART as 0x0304 frames at 30 Hz (docs/PROTOCOLS.md §6), built with
:mod:`rm_base.hardware.protocols.referee`, while the client is connected
(:mod:`rm_base.sim.operator_link`).
"""

from __future__ import annotations

from rm_base.hardware.protocols import referee as ref
from rm_base.sim.operator_link import OperatorLink

#: 0x0304 frames per second.
RATE_HZ = 30.0


class SimImageLink(OperatorLink[ref.KeyboardMouse]):
    """The image link's keyboard-and-mouse stream: nothing pressed at start."""

    def __init__(self, *, path: str, name: str = 'image_link') -> None:
        """Open the terminal. Raises: SimConfigError: it cannot be created."""
        super().__init__(
            ref.KeyboardMouse(0, 0, 0, False, False, 0), RATE_HZ, path=path, name=name
        )

    def _encode(self, state: ref.KeyboardMouse) -> bytes:
        return ref.encode_frame(*ref.encode_status(state, ref.ProtocolVersion.V2025))
