"""The damiao family as the motor registry sees it (rm_base/motors/registry.py)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.hardware.config import JointConfig
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.damiao.actuator import Damiao, Dm4310, Dm4340, Dm8009, Dm10010L
from rm_base.motors.damiao.sim_device import DamiaoDevice
from rm_base.motors.family import DeviceParts, MotorFamily, SimFamily
from rm_base.sim.config_values import can_id, flag, mit_limits, number
from rm_base.sim.errors import SimConfigError
from rm_base.sim.motor_params import MOTOR_DEFAULTS, MotorType

_MODELS = {'dm4310': 'DM4310', 'dm8009': 'DM8009'}
_MODES = {'mit': damiao.DmMode.MIT, 'pos_vel': damiao.DmMode.POS_VEL, 'vel': damiao.DmMode.VEL}


def _build(cfg: Mapping[str, Any], parts: DeviceParts) -> DamiaoDevice:
    name, motor_id = parts.name, parts.motor_id
    if motor_id > damiao.MAX_MOTOR_ID:
        # The feedback carries only the low nibble of the id.
        raise SimConfigError(f'{name}: Damiao id must be 0..15, got {motor_id}')
    dm_model = cfg.get('model', _MODELS[parts.sim_type])
    if not isinstance(dm_model, str):
        raise SimConfigError(f'{name}: model must be a string, got {dm_model!r}')
    limits = mit_limits(cfg, damiao.dm_limits(dm_model), name)
    mode_name = cfg.get('mode', 'mit')
    if mode_name not in _MODES:
        raise SimConfigError(f'{name}: mode must be one of {sorted(_MODES)}, got {mode_name!r}')
    timeout = number(cfg, 'command_timeout', None, name)
    if timeout is not None and timeout < 0.0:
        raise SimConfigError(f'{name}: command_timeout must be >= 0 s, got {timeout}')
    gains = {k: number(cfg, k, None, name) for k in ('vel_kp', 'vel_ki')}
    for key, value in gains.items():
        if value is not None and value < 0.0:
            raise SimConfigError(f'{name}: {key} must be >= 0, got {value}')
    pos_kp = number(cfg, 'pos_kp', 20.0, name)
    if pos_kp is None or pos_kp < 0.0:
        raise SimConfigError(f'{name}: pos_kp must be >= 0, got {pos_kp}')
    return DamiaoDevice(
        name,
        MotorType(parts.sim_type),
        motor_id,
        parts.model,
        limits,
        master_id=can_id(cfg, 'master_id', name, default=motor_id + 0x10),
        mode=_MODES[mode_name],
        enabled=flag(cfg, 'enabled', name),
        command_timeout=timeout,
        vel_kp=gains['vel_kp'],
        vel_ki=gains['vel_ki'],
        pos_kp=pos_kp,
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
        keys=frozenset(
            {
                'model',
                'master_id',
                'mode',
                'limits',
                'enabled',
                'command_timeout',
                'vel_kp',
                'vel_ki',
                'pos_kp',
            }
        ),
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
