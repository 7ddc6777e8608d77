"""The cheetah family as the motor registry sees it (rm_base/motors/registry.py)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.config.schema import Schema, boolean, integer
from rm_base.hardware.actuators.mit import LIMITS_KEY
from rm_base.motors.cheetah import protocol as cheetah
from rm_base.motors.cheetah.actuator import Cheetah
from rm_base.motors.cheetah.sim_device import CheetahDevice
from rm_base.motors.family import DeviceParts, MotorFamily, SimFamily
from rm_base.sim_devices.device import STD_ID_MAX
from rm_base.sim_devices.motor_params import MOTOR_DEFAULTS, MotorType

#: A simulated Cheetah driver's keys (``SimFamily.schema``).
SIM_SCHEMA = Schema((
    integer('master_id', cheetah.DEFAULT_MASTER_ID, ge=0, le=STD_ID_MAX,
            description='id of its replies'),
    LIMITS_KEY,
    boolean('enabled', False, description='in motor mode at the start (else it waits for enter)'),
    boolean('reply_voltage', False, description='replies carry the bus voltage (8 bytes, not 6)'),
))


def _build(values: Mapping[str, Any], parts: DeviceParts) -> CheetahDevice:
    return CheetahDevice(
        parts.name,
        MotorType(parts.sim_type),
        parts.motor_id,
        parts.model,
        cheetah.CHEETAH_DEFAULT_LIMITS.with_overrides(values['limits']),
        master_id=values['master_id'],
        enabled=values['enabled'],
        reply_voltage=values['reply_voltage'],
        **parts.common,
    )


FAMILY = MotorFamily(
    name='cheetah',
    actuators=(Cheetah,),
    sim=SimFamily(
        models={'cheetah': MOTOR_DEFAULTS[MotorType.CHEETAH]},
        schema=SIM_SCHEMA,
        build=_build,
        joint_types={'cheetah': ('cheetah', {})},
        shared_options=('master_id', 'limits'),
    ),
)
