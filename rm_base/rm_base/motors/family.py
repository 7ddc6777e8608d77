"""What the project knows about one motor family, in one record (see ``registry``)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rm_base.config.schema import Schema
from rm_base.hardware.families import GroupBuilder

if TYPE_CHECKING:
    from rm_base.hardware.actuators.base import Actuator
    from rm_base.hardware.config import JointConfig
    from rm_base.sim_devices.device import SimDevice
    from rm_base.sim_devices.motor import MotorModel
    from rm_base.sim_devices.motor_params import MotorParams



@dataclass(frozen=True)
class DeviceParts:
    """What every simulated motor has, read by the simulator before the family's builder.

    Attributes:
        name: the device's unique name.
        sim_type: the simulated motor type (a key of the family's ``models``).
        motor_id: ESC id (DJI) or CAN id.
        model: its physics, built from the type's defaults and the config's overrides.
        common: keyword arguments for :class:`~rm_base.sim_devices.device.SimDevice` (seed,
            overtemp_c).
    """

    name: str
    sim_type: str
    motor_id: int
    model: MotorModel
    common: dict[str, Any]


@dataclass(frozen=True)
class SimFamily:
    """How the simulator stands in for a family's motors.

    Attributes:
        models: simulated motor type -> default physics (output-shaft constants).
        schema: the device config keys of the family, beyond the common ones and the
            physics (rm_base.sim.device_config).
        build: (the schema's values, parts) -> the simulated device; raises
            SimConfigError.
        joint_types: hardware joint type -> (simulated type, extra device keys) for a
            joint without ``sim.type``; a joint type missing here has no simulated model.
        joint_type_of: the same for joints whose simulated type depends on their options
            (a ``damiao`` joint of any model); None: not this joint, look in joint_types.
        shared_options: joint options that describe the protocol, which the simulated
            device must get too (scales, master ids, limits).
        check_channel: checks that the family's devices among a bus's can share it,
            beyond the generic id checks (DJI command slots); raises SimConfigError.
    """

    models: Mapping[str, MotorParams]
    schema: Schema
    build: Callable[[Mapping[str, Any], DeviceParts], SimDevice]
    joint_types: Mapping[str, tuple[str, Mapping[str, Any]]] = field(default_factory=dict)
    joint_type_of: Callable[[JointConfig], tuple[str, Mapping[str, Any]] | None] | None = None
    shared_options: tuple[str, ...] = ()
    check_channel: Callable[[Sequence[SimDevice]], None] | None = None

    def simulated_type(self, joint: JointConfig) -> tuple[str, Mapping[str, Any]] | None:
        """(simulated type, extra device keys) of a hardware joint, None if it has none."""
        if self.joint_type_of is not None:
            found = self.joint_type_of(joint)
            if found is not None:
                return found
        return self.joint_types.get(joint.type)


@dataclass(frozen=True)
class MotorFamily:
    """One motor family: its joint types, how their frames are packed, its simulator.

    Attributes:
        name: the family's name (``dji``, ``damiao``...), unique among families.
        actuators: one :class:`~rm_base.hardware.actuators.base.Actuator` class per
            joint ``type`` of the robot config (the class's ``type_name``).
        build_groups: for families whose motors share command frames: builds the frame
            owners from the family's actuators; None: every actuator packs its own frame.
        sim: the simulated motors, None if the family cannot be simulated.
    """

    name: str
    actuators: tuple[type[Actuator], ...]
    build_groups: GroupBuilder | None = None
    sim: SimFamily | None = None

    def joint_types(self) -> Iterable[str]:
        """The joint ``type`` names of the family."""
        return (cls.type_name for cls in self.actuators)
