"""What the hardware layer asks of the motor families, as protocols.

The families (``rm_base.motors``) are built on this layer's actuators, so the registry
lives above it; CanHardware is handed the registry (the module ``rm_base.motors`` fits
:class:`MotorFamilies`) instead of importing it, and a family's shared frames are
:class:`SharedFrame` s.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

import can

from rm_base.hardware.actuators import Actuator
from rm_base.hardware.config import JointConfig, SafetyConfig


class SharedFrame(Protocol):
    """The owner of a command frame that several motors share (a DJI group)."""

    bus_name: str
    arbitration_id: int

    @property
    def name(self) -> str:
        """Readable name for logs (``can0/0x200``)."""
        ...

    def pack_command(self) -> can.Message:
        """The frame with every member's current command."""
        ...


#: Builds the shared frames of a family's actuators (those of the robot, that family's).
GroupBuilder = Callable[[Sequence[Actuator]], Sequence[SharedFrame]]


class JointFamily(Protocol):
    """What CanHardware reads of a motor family."""

    @property
    def name(self) -> str:
        """The family's name."""
        ...

    @property
    def build_groups(self) -> GroupBuilder | None:
        """How its actuators share command frames; None: each sends its own."""
        ...


class MotorFamilies(Protocol):
    """The motor families' registry as CanHardware asks it (the module ``rm_base.motors``).

    Both raise a ConfigError naming the known types for a type no family has.
    """

    def family_of(self, joint_type: str) -> JointFamily:
        """The family of a joint type."""
        ...

    def actuator_class(self, joint_type: str) -> Callable[[JointConfig, SafetyConfig], Actuator]:
        """The actuator class of a joint type."""
        ...
