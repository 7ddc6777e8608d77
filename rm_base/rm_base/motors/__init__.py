"""Motor families: one folder each, found through one registry (``registry``).

A family bundles its joint types (actuator classes), how its command frames are packed,
and how the simulator stands in for its motors (:class:`MotorFamily`). The hardware layer,
the bridge and the simulator ask the registry, never a family by name.
"""

from rm_base.hardware.families import GroupBuilder
from rm_base.motors.family import DeviceParts, MotorFamily, SimFamily
from rm_base.motors.registry import (
    BUILT_IN,
    ENTRY_POINT_GROUP,
    MotorFamilyError,
    UnknownTypeError,
    actuator_class,
    families,
    family_of,
    joint_types,
    reload,
    sim_family,
    sim_types,
)

__all__ = [
    'BUILT_IN',
    'ENTRY_POINT_GROUP',
    'DeviceParts',
    'GroupBuilder',
    'MotorFamily',
    'MotorFamilyError',
    'SimFamily',
    'UnknownTypeError',
    'actuator_class',
    'families',
    'family_of',
    'joint_types',
    'reload',
    'sim_family',
    'sim_types',
]
