"""Simulated motors from plain config dicts, and the check that they can share a bus."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from rm_base.hardware.errors import HardwareConfigError, ValueRangeError
from rm_base.hardware.protocols import cheetah, damiao, dji, mit
from rm_base.sim.devices import STD_ID_MAX, SimDevice
from rm_base.sim.dji_device import DjiDevice
from rm_base.sim.errors import SimConfigError
from rm_base.sim.mit_devices import CheetahDevice, DamiaoDevice
from rm_base.sim.motor import MotorModel, MotorParams, MotorType, motor_params

_DJI_KINDS = {
    MotorType.M3508: dji.DjiKind.C620,
    MotorType.M2006: dji.DjiKind.C610,
}
_DM_MODELS = {MotorType.DM4310: 'DM4310', MotorType.DM8009: 'DM8009'}
_PARAM_KEYS = frozenset(MotorParams.__dataclass_fields__)
_COMMON_KEYS = frozenset(
    {'type', 'id', 'name', 'initial_position', 'initial_velocity', 'overtemp_c'}
)
_FAMILY_KEYS = {
    'dji': frozenset(
        {
            'feedback_rate_hz',
            'command_timeout',
            'control',
            'raw_limit',
            'si_per_raw',
            'feedback_amps_per_raw',
        }
    ),
    'damiao': frozenset(
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
    'cheetah': frozenset({'master_id', 'limits', 'enabled', 'reply_voltage'}),
}


def _number(cfg: Mapping[str, Any], key: str, default: float | None, name: str) -> float | None:
    value = cfg.get(key, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SimConfigError(f'{name}: {key} must be a finite number, got {value!r}')
    return float(value)


def _int_id(cfg: Mapping[str, Any], key: str, name: str, default: int | None = None) -> int:
    value = cfg.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= STD_ID_MAX:
        raise SimConfigError(f'{name}: {key} must be an int in 0..0x7FF, got {value!r}')
    return value


def device_from_config(config: Mapping[str, Any], *, seed: int = 0) -> SimDevice:
    """Build a simulated motor from a plain dict.

    Keys (SI units; every key but ``type`` and ``id`` is optional):

    * ``type``: ``'m3508' | 'm2006' | 'gm6020' | 'dm4310' | 'dm8009' | 'cheetah'``.
    * ``id``: ESC id (DJI: C620/C610 1..8, GM6020 1..7) or CAN id (Damiao, Cheetah).
    * ``name``: unique name, default ``'<type>_<id>'``.
    * any :class:`~rm_base.sim.motor.MotorParams` field, e.g. ``load_inertia`` [kg·m²],
      ``viscous_friction`` [N·m·s/rad], ``coulomb_friction`` [N·m], ``max_current`` [A].
    * ``initial_position`` [rad] and ``initial_velocity`` [rad/s] at the output shaft.
    * ``overtemp_c``: cut-out temperature [°C]; default none for DJI and Cheetah,
      120 °C for Damiao (which then reports COIL_OVER_TEMPERATURE).
    * DJI: ``feedback_rate_hz`` (1000), ``command_timeout`` [s] (0.1; 0 or None = never),
      ``control`` (GM6020: ``'voltage'`` (default) or ``'current'``), and the
      UNVERIFIED scales of :func:`rm_base.hardware.protocols.dji.make_dji_spec`:
      ``raw_limit``, ``si_per_raw``, ``feedback_amps_per_raw``.
    * Damiao: ``model`` (default from the type, e.g. ``'DM4310'``), ``master_id``
      (default id + 0x10), ``mode`` (``'mit'`` default, ``'pos_vel'``, ``'vel'``),
      ``limits`` (``{'p_max': .., 'v_max': .., 't_max': ..}`` overrides), ``enabled``
      (False), ``command_timeout`` [s] (None), ``vel_kp``, ``vel_ki``, ``pos_kp``.
    * Cheetah: ``master_id`` (0), ``limits`` (default P ±12.5, V ±65, T ±18),
      ``enabled`` (False), ``reply_voltage`` (False: 6-byte reply).

    Args:
        config: the motor's dict.
        seed: seed of the device's random generator (garbage frames).

    Returns:
        The device.

    Raises:
        SimConfigError: a missing, unknown or invalid key.
    """
    if not isinstance(config, Mapping):
        raise SimConfigError(f'a motor config must be a mapping, got {config!r}')
    if 'type' not in config or 'id' not in config:
        raise SimConfigError(f'a motor config needs a type and an id, got {dict(config)!r}')
    try:
        motor_type = MotorType(config['type'])
    except ValueError:
        known = sorted(t.value for t in MotorType)
        raise SimConfigError(f'unknown motor type {config["type"]!r}; known: {known}') from None
    motor_id = _int_id(config, 'id', f'{motor_type.value} motor')
    name = config.get('name', f'{motor_type.value}_{motor_id}')
    if not isinstance(name, str) or not name:
        raise SimConfigError(f'motor name must be a non-empty string, got {name!r}')
    family = motor_type.family
    allowed = _COMMON_KEYS | _PARAM_KEYS | _FAMILY_KEYS[family]
    unknown = sorted(set(config) - allowed)
    if unknown:
        raise SimConfigError(f'{name}: unknown key(s) {unknown}; known: {sorted(allowed)}')

    params = motor_params(motor_type, **{k: config[k] for k in _PARAM_KEYS & set(config)})
    model = MotorModel(
        params,
        angle=_number(config, 'initial_position', 0.0, name),
        velocity=_number(config, 'initial_velocity', 0.0, name),
    )
    common: dict[str, Any] = {'seed': seed}
    if 'overtemp_c' in config:
        common['overtemp_c'] = _number(config, 'overtemp_c', None, name)
    parts = {
        'name': name,
        'motor_type': motor_type,
        'motor_id': motor_id,
        'model': model,
        'common': common,
    }
    try:
        if family == 'dji':
            return _dji_from_config(config, **parts)
        if family == 'damiao':
            return _damiao_from_config(config, **parts)
        return _cheetah_from_config(config, **parts)
    except (HardwareConfigError, ValueRangeError) as err:
        raise SimConfigError(f'{name}: {err}') from err


def _dji_from_config(
    cfg: Mapping[str, Any],
    *,
    name: str,
    motor_type: MotorType,
    motor_id: int,
    model: MotorModel,
    common: dict[str, Any],
) -> DjiDevice:
    control = cfg.get('control', 'voltage')
    if motor_type is MotorType.GM6020:
        if control not in ('voltage', 'current'):
            raise SimConfigError(f"{name}: control must be 'voltage' or 'current', got {control!r}")
        kind = dji.DjiKind.GM6020_VOLTAGE if control == 'voltage' else dji.DjiKind.GM6020_CURRENT
    elif 'control' in cfg:
        raise SimConfigError(f'{name}: only the GM6020 has a control mode')
    else:
        kind = _DJI_KINDS[motor_type]
    spec = dji.make_dji_spec(
        kind,
        raw_limit=cfg.get('raw_limit'),
        si_per_raw=cfg.get('si_per_raw'),
        feedback_amps_per_raw=cfg.get('feedback_amps_per_raw'),
    )
    spec.check_id(motor_id)
    rate = _number(cfg, 'feedback_rate_hz', 1000.0, name)
    if rate is None or rate <= 0.0:
        raise SimConfigError(f'{name}: feedback_rate_hz must be > 0, got {rate}')
    timeout = _number(cfg, 'command_timeout', 0.1, name)
    if timeout is not None and timeout < 0.0:
        raise SimConfigError(f'{name}: command_timeout must be >= 0 s, got {timeout}')
    return DjiDevice(
        name,
        motor_type,
        motor_id,
        model,
        spec,
        feedback_rate_hz=rate,
        command_timeout=timeout,
        **common,
    )


def _limits(cfg: Mapping[str, Any], base: mit.MitLimits, name: str) -> mit.MitLimits:
    overrides = cfg.get('limits')
    if overrides is not None and not isinstance(overrides, Mapping):
        raise SimConfigError(f'{name}: limits must be a mapping, got {overrides!r}')
    return base.with_overrides(dict(overrides) if overrides else None)


def _flag(cfg: Mapping[str, Any], key: str, name: str) -> bool:
    value = cfg.get(key, False)
    if not isinstance(value, bool):
        raise SimConfigError(f'{name}: {key} must be true or false, got {value!r}')
    return value


def _damiao_from_config(
    cfg: Mapping[str, Any],
    *,
    name: str,
    motor_type: MotorType,
    motor_id: int,
    model: MotorModel,
    common: dict[str, Any],
) -> DamiaoDevice:
    if motor_id > damiao.MAX_MOTOR_ID:
        # The feedback carries only the low nibble of the id.
        raise SimConfigError(f'{name}: Damiao id must be 0..15, got {motor_id}')
    dm_model = cfg.get('model', _DM_MODELS[motor_type])
    if not isinstance(dm_model, str):
        raise SimConfigError(f'{name}: model must be a string, got {dm_model!r}')
    limits = _limits(cfg, damiao.dm_limits(dm_model), name)
    mode_name = cfg.get('mode', 'mit')
    modes = {'mit': damiao.DmMode.MIT, 'pos_vel': damiao.DmMode.POS_VEL, 'vel': damiao.DmMode.VEL}
    if mode_name not in modes:
        raise SimConfigError(f'{name}: mode must be one of {sorted(modes)}, got {mode_name!r}')
    timeout = _number(cfg, 'command_timeout', None, name)
    if timeout is not None and timeout < 0.0:
        raise SimConfigError(f'{name}: command_timeout must be >= 0 s, got {timeout}')
    gains = {k: _number(cfg, k, None, name) for k in ('vel_kp', 'vel_ki')}
    for key, value in gains.items():
        if value is not None and value < 0.0:
            raise SimConfigError(f'{name}: {key} must be >= 0, got {value}')
    pos_kp = _number(cfg, 'pos_kp', 20.0, name)
    if pos_kp is None or pos_kp < 0.0:
        raise SimConfigError(f'{name}: pos_kp must be >= 0, got {pos_kp}')
    return DamiaoDevice(
        name,
        motor_type,
        motor_id,
        model,
        limits,
        master_id=_int_id(cfg, 'master_id', name, default=motor_id + 0x10),
        mode=modes[mode_name],
        enabled=_flag(cfg, 'enabled', name),
        command_timeout=timeout,
        vel_kp=gains['vel_kp'],
        vel_ki=gains['vel_ki'],
        pos_kp=pos_kp,
        **common,
    )


def _cheetah_from_config(
    cfg: Mapping[str, Any],
    *,
    name: str,
    motor_type: MotorType,
    motor_id: int,
    model: MotorModel,
    common: dict[str, Any],
) -> CheetahDevice:
    return CheetahDevice(
        name,
        motor_type,
        motor_id,
        model,
        _limits(cfg, cheetah.CHEETAH_DEFAULT_LIMITS, name),
        master_id=_int_id(cfg, 'master_id', name, default=cheetah.DEFAULT_MASTER_ID),
        enabled=_flag(cfg, 'enabled', name),
        reply_voltage=_flag(cfg, 'reply_voltage', name),
        **common,
    )


def check_channel(devices: list[SimDevice]) -> None:
    """Check that the devices can share one bus: no two send on one id, no command clash.

    Raises:
        SimConfigError: two devices use one feedback id or one DJI command slot, or one
            device's command id is another one's feedback id; the message names both.
    """
    djis = [d for d in devices if isinstance(d, DjiDevice)]
    try:
        dji.check_collisions([(d.spec.kind, d.motor_id) for d in djis], [d.name for d in djis])
    except (HardwareConfigError, ValueRangeError) as err:
        raise SimConfigError(str(err)) from err
    names: dict[str, SimDevice] = {}
    sent: dict[int, SimDevice] = {}
    for dev in devices:
        if dev.name in names:
            raise SimConfigError(f'two motors are named {dev.name!r}')
        names[dev.name] = dev
        for can_id in dev.transmit_ids:
            if can_id in sent:
                raise SimConfigError(
                    f'{dev.name} and {sent[can_id].name} both send on id 0x{can_id:03X}'
                )
            sent[can_id] = dev
    listened: dict[int, SimDevice] = {}
    for dev in devices:
        for can_id in dev.listen_ids:
            if can_id in sent:
                raise SimConfigError(
                    f'{dev.name} listens on 0x{can_id:03X}, where {sent[can_id].name} sends'
                )
            other = listened.get(can_id)
            # DJI ESCs share group frames by design (distinct slots, checked above).
            if other is not None and not (isinstance(other, DjiDevice) and dev in djis):
                raise SimConfigError(
                    f'{dev.name} and {other.name} both take commands on 0x{can_id:03X}'
                )
            listened[can_id] = dev
