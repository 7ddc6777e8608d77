"""What a simulated motor is: its physical constants, and the built-in models' values.

Output-shaft values (what users configure); :mod:`rm_base.sim_devices.motor` turns them into the
rotor-side model that moves.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from enum import Enum

from rm_base.config.schema import Key, Schema, number
from rm_base.sim_devices.errors import SimConfigError


class MotorType(Enum):
    """The built-in simulated motor models; the value is the config name.

    Their physics are in MOTOR_DEFAULTS; their families (rm_base.motors) say how each one
    talks on the bus.
    """

    M3508 = 'm3508'
    M2006 = 'm2006'
    GM6020 = 'gm6020'
    DM4310 = 'dm4310'
    DM8009 = 'dm8009'
    CHEETAH = 'cheetah'


@dataclass(frozen=True)
class MotorParams:
    """Physical constants of one motor and its driver; output-shaft values unless noted.

    The fields, their units and bounds are :data:`PHYSICS_SCHEMA`'s keys (checked here).
    """

    gear_ratio: float
    torque_constant: float
    back_emf_constant: float
    resistance: float
    supply_voltage: float
    max_current: float
    rotor_inertia: float
    load_inertia: float = 0.0
    viscous_friction: float = 0.0
    coulomb_friction: float = 0.0
    thermal_resistance: float = 2.0
    thermal_capacitance: float = 150.0
    ambient_temperature: float = 25.0

    def __post_init__(self) -> None:
        PHYSICS_SCHEMA.read('motor parameter', dataclasses.asdict(self), SimConfigError)

    def replace(self, **overrides: object) -> MotorParams:
        """Return a copy with some fields replaced (validated like the constructor).

        Raises:
            SimConfigError: an unknown field name or an invalid value.
        """
        names = PHYSICS_SCHEMA.names
        unknown = sorted(set(overrides) - names)
        if unknown:
            raise SimConfigError(f'unknown motor parameter(s) {unknown}; known: {sorted(names)}')
        values = PHYSICS_SCHEMA.read(
            'motor parameter', {**dataclasses.asdict(self), **overrides}, SimConfigError
        )
        return dataclasses.replace(self, **values)

    @property
    def inertia(self) -> float:
        """Total inertia on the rotor side [kg·m²]: rotor plus reflected load."""
        return self.rotor_inertia + self.load_inertia / self.gear_ratio**2

    @property
    def output_inertia(self) -> float:
        """Total inertia seen at the output shaft [kg·m²]."""
        return self.inertia * self.gear_ratio**2


def _physics_key(name: str, unit: str, bound: str, description: str) -> Key:
    bounds = {'>': {'gt': 0.0}, '>=': {'ge': 0.0}, '': {}}[bound]
    return number(name, None, unit=unit, description=description, **bounds)


#: The physics of ``joints.<joint>.sim`` / a world's motor: :class:`MotorParams`' fields,
#: each defaulting to the simulated type's value.
PHYSICS_SCHEMA = Schema(tuple(_physics_key(*row) for row in (
    ('gear_ratio', '', '>', 'rotor turns per output turn (1: direct drive)'),
    ('torque_constant', 'N·m/A', '>', 'Kt at the output shaft'),
    ('back_emf_constant', 'V/(rad/s)', '>=', 'Ke at the output shaft'),
    ('resistance', 'Ohm', '>', 'winding resistance seen by the driver'),
    ('supply_voltage', 'V', '>', 'bus voltage'),
    ('max_current', 'A', '>', 'driver current limit'),
    ('rotor_inertia', 'kg·m²', '>', 'the rotor alone, rotor side'),
    ('load_inertia', 'kg·m²', '>=', 'what the output shaft drives'),
    ('viscous_friction', 'N·m·s/rad', '>=', 'at the output shaft'),
    ('coulomb_friction', 'N·m', '>=', 'at the output shaft'),
    ('thermal_resistance', 'K/W', '>', 'winding to ambient'),
    ('thermal_capacitance', 'J/K', '>', 'of the winding'),
    ('ambient_temperature', 'degC', '', 'ambient, and the winding at the start'),
)))


# Approximate catalogue values (datasheets and team measurements, rounded); every one can be
# overridden per motor from the config. Gear ratios and torque constants follow
# docs/PROTOCOLS.md §1.5 and §2; back-EMF constants are chosen so that the no-load output speed at
# 24 V matches the datasheets (M3508 ~480 rpm, M2006 ~500 rpm, GM6020 ~320 rpm,
# DM4310 ~200 rpm); inertias and frictions are order-of-magnitude estimates.
MOTOR_DEFAULTS: dict[MotorType, MotorParams] = {
    MotorType.M3508: MotorParams(
        gear_ratio=3591.0 / 187.0,
        torque_constant=0.3,
        back_emf_constant=0.45,
        resistance=0.194,
        supply_voltage=24.0,
        max_current=20.0,
        rotor_inertia=1.2e-5,
        viscous_friction=2.5e-3,
        coulomb_friction=0.1,
        thermal_resistance=1.5,
        thermal_capacitance=200.0,
    ),
    MotorType.M2006: MotorParams(
        gear_ratio=36.0,
        torque_constant=0.18,
        back_emf_constant=0.42,
        resistance=0.5,
        supply_voltage=24.0,
        max_current=10.0,
        rotor_inertia=2.5e-6,
        viscous_friction=1.0e-3,
        coulomb_friction=0.04,
        thermal_resistance=4.0,
        thermal_capacitance=60.0,
    ),
    MotorType.GM6020: MotorParams(
        gear_ratio=1.0,
        torque_constant=0.741,
        back_emf_constant=0.70,
        resistance=1.8,
        supply_voltage=24.0,
        max_current=3.0,
        rotor_inertia=2.0e-4,
        viscous_friction=2.0e-3,
        coulomb_friction=0.02,
        thermal_resistance=2.5,
        thermal_capacitance=150.0,
    ),
    MotorType.DM4310: MotorParams(
        gear_ratio=10.0,
        torque_constant=0.945,
        back_emf_constant=1.05,
        resistance=1.3,
        supply_voltage=24.0,
        max_current=8.0,
        rotor_inertia=1.5e-5,
        viscous_friction=5.0e-3,
        coulomb_friction=0.05,
        thermal_resistance=3.0,
        thermal_capacitance=80.0,
    ),
    MotorType.DM8009: MotorParams(
        gear_ratio=9.0,
        torque_constant=1.6,
        back_emf_constant=1.1,
        resistance=0.35,
        supply_voltage=24.0,
        max_current=25.0,
        rotor_inertia=1.2e-4,
        viscous_friction=2.0e-2,
        coulomb_friction=0.3,
        thermal_resistance=1.2,
        thermal_capacitance=400.0,
    ),
    MotorType.CHEETAH: MotorParams(
        gear_ratio=6.0,
        torque_constant=0.45,
        back_emf_constant=0.45,
        resistance=0.25,
        supply_voltage=24.0,
        max_current=40.0,
        rotor_inertia=6.0e-5,
        viscous_friction=1.0e-2,
        coulomb_friction=0.1,
        thermal_resistance=1.5,
        thermal_capacitance=200.0,
    ),
}


def motor_params(motor_type: MotorType | str, **overrides: float) -> MotorParams:
    """Return the default parameters of a motor type, with overrides applied.

    Args:
        motor_type: a :class:`MotorType` or its config name (``'m3508'``).
        **overrides: :class:`MotorParams` fields to replace (SI units).

    Raises:
        SimConfigError: an unknown type or parameter, or an invalid value.
    """
    try:
        kind = MotorType(motor_type)
    except ValueError:
        known = sorted(t.value for t in MotorType)
        raise SimConfigError(f'unknown motor type {motor_type!r}; known: {known}') from None
    return MOTOR_DEFAULTS[kind].replace(**overrides)
