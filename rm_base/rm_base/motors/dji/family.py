"""The dji family as the motor registry sees it (rm_base/motors/registry.py)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rm_base.hardware.actuators import Actuator
from rm_base.hardware.errors import HardwareConfigError, ValueRangeError
from rm_base.motors.dji import protocol as dji
from rm_base.motors.dji.actuator import M2006, M3508, DjiActuator, Gm6020Current, Gm6020Voltage
from rm_base.motors.dji.groups import DjiCommandGroup, build_dji_groups
from rm_base.motors.dji.sim_device import DjiDevice
from rm_base.motors.family import DeviceParts, MotorFamily, SimFamily
from rm_base.sim.config_values import number
from rm_base.sim.devices import SimDevice
from rm_base.sim.errors import SimConfigError
from rm_base.sim.motor_params import MOTOR_DEFAULTS, MotorType

_KINDS = {'m3508': dji.DjiKind.C620, 'm2006': dji.DjiKind.C610}


def _build(cfg: Mapping[str, Any], parts: DeviceParts) -> DjiDevice:
    name = parts.name
    control = cfg.get('control', 'voltage')
    if parts.sim_type == 'gm6020':
        if control not in ('voltage', 'current'):
            raise SimConfigError(f"{name}: control must be 'voltage' or 'current', got {control!r}")
        kind = dji.DjiKind.GM6020_VOLTAGE if control == 'voltage' else dji.DjiKind.GM6020_CURRENT
    elif 'control' in cfg:
        raise SimConfigError(f'{name}: only the GM6020 has a control mode')
    else:
        kind = _KINDS[parts.sim_type]
    spec = dji.make_dji_spec(
        kind,
        raw_limit=cfg.get('raw_limit'),
        si_per_raw=cfg.get('si_per_raw'),
        feedback_amps_per_raw=cfg.get('feedback_amps_per_raw'),
    )
    spec.check_id(parts.motor_id)
    rate = number(cfg, 'feedback_rate_hz', 1000.0, name)
    if rate is None or rate <= 0.0:
        raise SimConfigError(f'{name}: feedback_rate_hz must be > 0, got {rate}')
    timeout = number(cfg, 'command_timeout', 0.1, name)
    if timeout is not None and timeout < 0.0:
        raise SimConfigError(f'{name}: command_timeout must be >= 0 s, got {timeout}')
    return DjiDevice(
        name,
        MotorType(parts.sim_type),
        parts.motor_id,
        parts.model,
        spec,
        feedback_rate_hz=rate,
        command_timeout=timeout,
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
        keys=frozenset(
            {
                'feedback_rate_hz',
                'command_timeout',
                'control',
                'raw_limit',
                'si_per_raw',
                'feedback_amps_per_raw',
            }
        ),
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
