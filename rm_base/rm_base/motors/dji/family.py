"""The dji family as the motor registry sees it (rm_base/motors/registry.py)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rm_base.config.schema import Schema, number, string
from rm_base.hardware.actuators import Actuator
from rm_base.hardware.errors import HardwareConfigError, ValueRangeError
from rm_base.motors.dji import protocol as dji
from rm_base.motors.dji.actuator import (
    M2006,
    M3508,
    SCALE_KEYS,
    DjiActuator,
    Gm6020Current,
    Gm6020Voltage,
)
from rm_base.motors.dji.groups import DjiCommandGroup, build_dji_groups
from rm_base.motors.dji.sim_device import DjiDevice
from rm_base.motors.family import DeviceParts, MotorFamily, SimFamily
from rm_base.sim_devices.device import SimDevice
from rm_base.sim_devices.errors import SimConfigError
from rm_base.sim_devices.motor_params import MOTOR_DEFAULTS, MotorType

_KINDS = {'m3508': dji.DjiKind.C620, 'm2006': dji.DjiKind.C610}


#: A simulated DJI ESC's keys (``SimFamily.schema``); the scales must match the joint's.
SIM_SCHEMA = Schema((
    number('feedback_rate_hz', 1000.0, unit='Hz', gt=0.0, description='feedback frames per second'),
    number('command_timeout', 0.1, unit='s', ge=0.0,
           description='no command for this long: zero current (0: never)'),
    string('control', None, choices=('voltage', 'current'),
           description='GM6020 only: what its command sets; default voltage'),
    *SCALE_KEYS,
))


def _build(values: Mapping[str, Any], parts: DeviceParts) -> DjiDevice:
    control = values['control']
    if parts.sim_type == 'gm6020':
        current = control == 'current'
        kind = dji.DjiKind.GM6020_CURRENT if current else dji.DjiKind.GM6020_VOLTAGE
    elif control is not None:
        raise SimConfigError(f'{parts.name}: only the GM6020 has a control mode')
    else:
        kind = _KINDS[parts.sim_type]
    spec = dji.make_dji_spec(
        kind,
        raw_limit=values['raw_limit'],
        si_per_raw=values['si_per_raw'],
        feedback_amps_per_raw=values['feedback_amps_per_raw'],
    )
    spec.check_id(parts.motor_id)
    return DjiDevice(
        parts.name,
        MotorType(parts.sim_type),
        parts.motor_id,
        parts.model,
        spec,
        feedback_rate_hz=values['feedback_rate_hz'],
        command_timeout=values['command_timeout'],
        **parts.common,
    )


def _groups(actuators: Sequence[Actuator]) -> list[DjiCommandGroup]:
    djis = [a for a in actuators if isinstance(a, DjiActuator)]
    if len(djis) != len(actuators):
        raise TypeError('DJI command groups take DJI actuators only')
    return build_dji_groups(djis)


def _check_channel(devices: Sequence[SimDevice]) -> None:
    djis = [d for d in devices if isinstance(d, DjiDevice)]
    try:
        dji.check_collisions([(d.spec.kind, d.motor_id) for d in djis], [d.name for d in djis])
    except (HardwareConfigError, ValueRangeError) as err:
        raise SimConfigError(str(err)) from err


FAMILY = MotorFamily(
    name='dji',
    actuators=(M3508, M2006, Gm6020Voltage, Gm6020Current),
    build_groups=_groups,
    sim=SimFamily(
        models={
            t.value: MOTOR_DEFAULTS[t] for t in (MotorType.M3508, MotorType.M2006, MotorType.GM6020)
        },
        schema=SIM_SCHEMA,
        build=_build,
        joint_types={
            'm3508': ('m3508', {}),
            'm2006': ('m2006', {}),
            'gm6020': ('gm6020', {'control': 'voltage'}),
            'gm6020_current': ('gm6020', {'control': 'current'}),
        },
        shared_options=('raw_limit', 'si_per_raw', 'feedback_amps_per_raw'),
        check_channel=_check_channel,
    ),
)
