"""The motor families the robot can drive, found in one table and through entry points.

The built-in families live in ``rm_base/motors/<family>/``, each ``family`` module exposing
``FAMILY`` (a :class:`~rm_base.motors.family.MotorFamily`). A package of its own adds a
family without touching rm_base by declaring an entry point, as python-can's interfaces
do::

    entry_points={'rm_base.motor_families': ['acme = acme_motors.family:FAMILY']}

Families load on first use (the family modules import the hardware layer, which asks the
registry for its joint types).
"""

from __future__ import annotations

import functools
import importlib
from importlib.metadata import entry_points

from rm_base.errors import ConfigError
from rm_base.motors.family import MotorFamily, SimFamily

#: The entry point group of third-party motor families.
ENTRY_POINT_GROUP = 'rm_base.motor_families'

#: Built-in families: name -> module holding ``FAMILY``.
BUILT_IN = {
    'dji': 'rm_base.motors.dji.family',
    'damiao': 'rm_base.motors.damiao.family',
    'cheetah': 'rm_base.motors.cheetah.family',
    'piper': 'rm_base.motors.piper.family',
    'lk': 'rm_base.motors.lk.family',
}


class MotorFamilyError(ConfigError):
    """A family that cannot be registered (a name or joint type already taken, bad entry)."""


class UnknownTypeError(ConfigError):
    """A joint type or simulated motor type no registered family has."""


@functools.cache
def families() -> dict[str, MotorFamily]:
    """Every registered family by name: the built-in ones, then the entry points'.

    Raises:
        MotorFamilyError: an entry point does not load to a MotorFamily, or two families
            share a name, a joint type or a simulated motor type.
    """
    found = [importlib.import_module(module).FAMILY for module in BUILT_IN.values()]
    for point in entry_points(group=ENTRY_POINT_GROUP):
        try:
            family = point.load()
        except Exception as err:
            raise MotorFamilyError(
                f'motor family entry point {point.name!r} ({point.value}) does not load: '
                f'{type(err).__name__}: {err}'
            ) from err
        if not isinstance(family, MotorFamily):
            raise MotorFamilyError(
                f'motor family entry point {point.name!r} ({point.value}) is a '
                f'{type(family).__name__}, not a MotorFamily'
            )
        found.append(family)
    return _checked(found)


def _checked(found: list[MotorFamily]) -> dict[str, MotorFamily]:
    by_name: dict[str, MotorFamily] = {}
    owner: dict[str, str] = {}  # joint type or simulated type -> family
    for family in found:
        if family.name in by_name:
            raise MotorFamilyError(f'two motor families are named {family.name!r}')
        by_name[family.name] = family
        names = [f'joint type {t!r}' for t in family.joint_types()]
        if family.sim is not None:
            names += [f'simulated motor type {t!r}' for t in family.sim.models]
        for name in names:
            if name in owner:
                raise MotorFamilyError(
                    f'motor families {owner[name]!r} and {family.name!r} both define {name}'
                )
            owner[name] = family.name
    return by_name


@functools.cache
def _actuator_types() -> dict[str, tuple[MotorFamily, type]]:
    return {cls.type_name: (f, cls) for f in families().values() for cls in f.actuators}


def joint_types() -> list[str]:
    """Every joint ``type`` a robot config may name, sorted."""
    return sorted(_actuator_types())


def actuator_class(joint_type: str) -> type:
    """The Actuator class of a joint ``type``.

    Raises:
        UnknownTypeError: no family has that joint type (the message lists the known).
    """
    entry = _actuator_types().get(joint_type) if isinstance(joint_type, str) else None
    if entry is None:
        raise UnknownTypeError(
            f'type {joint_type!r} is unknown; known: {", ".join(joint_types())}'
        )
    return entry[1]


def family_of(joint_type: str) -> MotorFamily:
    """The family of a joint ``type`` (raises UnknownTypeError as ``actuator_class``)."""
    actuator_class(joint_type)
    return _actuator_types()[joint_type][0]


def sim_types() -> list[str]:
    """Every simulated motor type, sorted."""
    return sorted(t for f in families().values() if f.sim is not None for t in f.sim.models)


def sim_family(sim_type: str) -> SimFamily:
    """The simulator side of the family that has simulated motor type ``sim_type``.

    Raises:
        UnknownTypeError: no family simulates that type (the message lists the known).
    """
    for family in families().values():
        if family.sim is not None and isinstance(sim_type, str) and sim_type in family.sim.models:
            return family.sim
    raise UnknownTypeError(f'unknown motor type {sim_type!r}; known: {sim_types()}')


def reload() -> None:
    """Forget the loaded families (after installing a package that adds one; tests)."""
    families.cache_clear()
    _actuator_types.cache_clear()
