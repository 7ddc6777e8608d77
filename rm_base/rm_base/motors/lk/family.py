"""The LK family as the motor registry sees it (rm_base/motors/registry.py)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.config.schema import Schema, integer, number, string
from rm_base.hardware.config import JointConfig
from rm_base.motors.family import DeviceParts, MotorFamily, SimFamily
from rm_base.motors.lk import protocol as lk
from rm_base.motors.lk.actuator import MODELS, LkActuator, Mf9025, Mg4010
from rm_base.motors.lk.sim_device import LkDevice
from rm_base.sim_devices.errors import SimConfigError
from rm_base.sim_devices.motor_params import MotorParams

#: Simulated models' physics, output side; order-of-magnitude values chosen to match the
#: actuator's defaults (no-load speed, Kt, peak torque).
SIM_MODELS: dict[str, MotorParams] = {
    'mf9025': MotorParams(
        gear_ratio=1.0, torque_constant=0.32, back_emf_constant=0.65, resistance=0.5,
        supply_voltage=24.0, max_current=16.0, rotor_inertia=1.5e-3,
        viscous_friction=2.0e-3, coulomb_friction=0.02,
    ),
    'mg4010': MotorParams(
        gear_ratio=10.0, torque_constant=0.7, back_emf_constant=1.8, resistance=1.0,
        supply_voltage=24.0, max_current=6.5, rotor_inertia=3.0e-5,
        viscous_friction=5.0e-3, coulomb_friction=0.05,
    ),
}
_SERIES = {'mf9025': 'mf', 'mg4010': 'mg'}

#: A simulated LK motor's keys (``SimFamily.schema``).
SIM_SCHEMA = Schema((
    string('model', None, nonempty=True, description="the joint's model (shared with it)"),
    string('current_scale', None, choices=tuple(lk.CURRENT_SCALES),
           description="iq's amperes as its firmware counts them; default its series'"),
    integer('encoder_bits', None, ge=14, le=16, description='encoder width; default 16'),
    number('min_voltage', 18.0, unit='V', ge=0.0,
           description='below this supply it reports under-voltage and stops its output'),
    number('speed_kp', None, unit='N·m·s/rad', ge=0.0,
           description='its own speed loop (0xA2..0xA8); default ~100 rad/s bandwidth'),
    number('speed_ki', None, unit='N·m/rad', ge=0.0,
           description="its speed loop's integral gain; default speed_kp x 25"),
    number('position_kp', 20.0, unit='1/s', ge=0.0,
           description='its own position loop (0xA3..0xA8)'),
))


def _build(values: Mapping[str, Any], parts: DeviceParts) -> LkDevice:
    if not lk.MIN_MOTOR_ID <= parts.motor_id <= lk.MAX_MOTOR_ID:
        raise SimConfigError(f'{parts.name}: LK id must be 1..32, got {parts.motor_id}')
    scale = values['current_scale'] or _SERIES[parts.sim_type]
    return LkDevice(
        parts.name,
        parts.sim_type,
        parts.motor_id,
        parts.model,
        scale=lk.CURRENT_SCALES[scale],
        encoder_bits=values['encoder_bits'] or 16,
        min_voltage=values['min_voltage'],
        speed_kp=values['speed_kp'],
        speed_ki=values['speed_ki'],
        position_kp=values['position_kp'],
        **parts.common,
    )


def _generic_joint(joint: JointConfig) -> tuple[str, Mapping[str, Any]] | None:
    """A ``lk`` joint: the simulated motor of its model, else of its current scale."""
    if joint.type != LkActuator.type_name:
        return None
    model = str(joint.options.get('model', '')).upper()
    if model in MODELS:
        return model.lower(), {}
    return ('mg4010' if joint.options.get('current_scale') == 'mg' else 'mf9025'), {}


FAMILY = MotorFamily(
    name='lk',
    actuators=(LkActuator, Mf9025, Mg4010),
    sim=SimFamily(
        models=SIM_MODELS,
        schema=SIM_SCHEMA,
        build=_build,
        joint_types={'mf9025': ('mf9025', {}), 'mg4010': ('mg4010', {})},
        joint_type_of=_generic_joint,
        shared_options=('model', 'current_scale', 'encoder_bits'),
    ),
)
