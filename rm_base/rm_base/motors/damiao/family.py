"""The damiao family as the motor registry sees it (rm_base/motors/registry.py)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.config.schema import Schema, boolean, integer, number, string
from rm_base.hardware.actuators.mit import LIMITS_KEY
from rm_base.hardware.config import JointConfig
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.damiao.actuator import Damiao, Dm4310, Dm4340, Dm8009, Dm10010L
from rm_base.motors.damiao.sim_device import DamiaoDevice
from rm_base.motors.family import DeviceParts, MotorFamily, SimFamily
from rm_base.sim_devices.device import STD_ID_MAX
from rm_base.sim_devices.errors import SimConfigError
from rm_base.sim_devices.motor_params import MOTOR_DEFAULTS, MotorType

_MODELS = {'dm4310': 'DM4310', 'dm8009': 'DM8009'}
_MODES = {'mit': damiao.DmMode.MIT, 'pos_vel': damiao.DmMode.POS_VEL, 'vel': damiao.DmMode.VEL}


#: A simulated Damiao motor's keys (``SimFamily.schema``).
SIM_SCHEMA = Schema((
    string('model', None, nonempty=True,
           description="its model (DM4310, DM8009...: its MIT ranges); default the type's"),
    integer('master_id', None, ge=0, le=STD_ID_MAX,
            description='id of its feedback frames; default id + 0x10'),
    string('mode', 'mit', choices=tuple(_MODES), description='control mode at the start'),
    LIMITS_KEY,
    boolean('enabled', False, description='enabled at the start (else it waits for enable)'),
    number('command_timeout', None, unit='s', ge=0.0,
           description='TIMEOUT register: enabled and no command for this long -> '
           'COMMUNICATION_LOST; none or 0: never'),
    number('vel_kp', None, unit='N·m·s/rad', ge=0.0,
           description='internal velocity loop gain (POS_VEL, VEL); default ~100 rad/s '
           'bandwidth on the inertia'),
    number('vel_ki', None, unit='N·m/rad', ge=0.0,
           description='internal velocity loop integral gain; default vel_kp x 25'),
    number('pos_kp', 20.0, unit='1/s', ge=0.0, description='internal position loop gain (POS_VEL)'),
))


def _build(values: Mapping[str, Any], parts: DeviceParts) -> DamiaoDevice:
    name, motor_id = parts.name, parts.motor_id
    if motor_id > damiao.MAX_MOTOR_ID:
        # The feedback carries only the low nibble of the id.
        raise SimConfigError(f'{name}: Damiao id must be 0..15, got {motor_id}')
    model = values['model'] or _MODELS[parts.sim_type]
    master_id = values['master_id']
    return DamiaoDevice(
        name,
        MotorType(parts.sim_type),
        motor_id,
        parts.model,
        damiao.dm_limits(model).with_overrides(values['limits']),
        master_id=motor_id + 0x10 if master_id is None else master_id,
        mode=_MODES[values['mode']],
        enabled=values['enabled'],
        command_timeout=values['command_timeout'],
        vel_kp=values['vel_kp'],
        vel_ki=values['vel_ki'],
        pos_kp=values['pos_kp'],
        **parts.common,
    )


def _generic_joint(joint: JointConfig) -> tuple[str, Mapping[str, Any]] | None:
    """A ``damiao`` joint of any model: the simulated motor of its size class."""
    if joint.type != Damiao.type_name:
        return None
    model = str(joint.options.get('model', '')).upper()
    return ('dm8009' if model.startswith(('DM8', 'DM10', 'DM6')) else 'dm4310'), {}


FAMILY = MotorFamily(
    name='damiao',
    actuators=(Damiao, Dm4310, Dm4340, Dm8009, Dm10010L),
    sim=SimFamily(
        models={t.value: MOTOR_DEFAULTS[t] for t in (MotorType.DM4310, MotorType.DM8009)},
        schema=SIM_SCHEMA,
        build=_build,
        joint_types={
            'dm4310': ('dm4310', {}),
            'dm4340': ('dm4310', {'model': 'DM4340'}),
            'dm8009': ('dm8009', {}),
            'dm10010l': ('dm8009', {'model': 'DM10010L'}),
        },
        joint_type_of=_generic_joint,
        shared_options=('master_id', 'limits', 'model'),
    ),
)
