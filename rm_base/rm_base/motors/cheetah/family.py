"""The cheetah family as the motor registry sees it (rm_base/motors/registry.py)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.motors.cheetah import protocol as cheetah
from rm_base.motors.cheetah.actuator import Cheetah
from rm_base.motors.cheetah.sim_device import CheetahDevice
from rm_base.motors.family import DeviceParts, MotorFamily, SimFamily
from rm_base.sim.config_values import can_id, flag, mit_limits
from rm_base.sim.motor_params import MOTOR_DEFAULTS, MotorType


def _build(cfg: Mapping[str, Any], parts: DeviceParts) -> CheetahDevice:
    name = parts.name
    return CheetahDevice(
        name,
        MotorType(parts.sim_type),
        parts.motor_id,
        parts.model,
        mit_limits(cfg, cheetah.CHEETAH_DEFAULT_LIMITS, name),
        master_id=can_id(cfg, 'master_id', name, default=cheetah.DEFAULT_MASTER_ID),
        enabled=flag(cfg, 'enabled', name),
        reply_voltage=flag(cfg, 'reply_voltage', name),
        **parts.common,
    )


FAMILY = MotorFamily(
    name='cheetah',
    actuators=(Cheetah,),
    sim=SimFamily(
        models={'cheetah': MOTOR_DEFAULTS[MotorType.CHEETAH]},
        keys=frozenset({'master_id', 'limits', 'enabled', 'reply_voltage'}),
        build=_build,
        joint_types={'cheetah': ('cheetah', {})},
        shared_options=('master_id', 'limits'),
    ),
)
