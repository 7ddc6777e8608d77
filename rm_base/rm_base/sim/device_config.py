"""Simulated motors from plain config dicts, and the check that they can share a bus.

The keys every motor has are read here; the rest belong to the motor's family, which
builds the device (``rm_base.motors``: one registry of families).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.hardware.errors import HardwareConfigError, ValueRangeError
from rm_base.motors import DeviceParts, UnknownTypeError, families, sim_family
from rm_base.sim.config_values import can_id, number
from rm_base.sim.devices import SimDevice
from rm_base.sim.errors import SimConfigError
from rm_base.sim.motor import MotorModel
from rm_base.sim.motor_params import MotorParams

_PARAM_KEYS = frozenset(MotorParams.__dataclass_fields__)
_COMMON_KEYS = frozenset(
    {'type', 'id', 'name', 'initial_position', 'initial_velocity', 'overtemp_c'}
)


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
      UNVERIFIED scales of :func:`rm_base.motors.dji.protocol.make_dji_spec`:
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
    sim_type = config['type']
    try:
        family = sim_family(sim_type)
    except UnknownTypeError as err:
        raise SimConfigError(str(err)) from None
    motor_id = can_id(config, 'id', f'{sim_type} motor')
    name = config.get('name', f'{sim_type}_{motor_id}')
    if not isinstance(name, str) or not name:
        raise SimConfigError(f'motor name must be a non-empty string, got {name!r}')
    allowed = _COMMON_KEYS | _PARAM_KEYS | family.keys
    unknown = sorted(set(config) - allowed)
    if unknown:
        raise SimConfigError(f'{name}: unknown key(s) {unknown}; known: {sorted(allowed)}')

    params = family.models[sim_type].replace(**{k: config[k] for k in _PARAM_KEYS & set(config)})
    model = MotorModel(
        params,
        angle=number(config, 'initial_position', 0.0, name),
        velocity=number(config, 'initial_velocity', 0.0, name),
    )
    common: dict[str, Any] = {'seed': seed}
    if 'overtemp_c' in config:
        common['overtemp_c'] = number(config, 'overtemp_c', None, name)
    try:
        return family.build(config, DeviceParts(name, sim_type, motor_id, model, common))
    except (HardwareConfigError, ValueRangeError) as err:
        raise SimConfigError(f'{name}: {err}') from err


def check_channel(devices: list[SimDevice]) -> None:
    """Check that the devices can share one bus: no two send on one id, no command clash.

    Raises:
        SimConfigError: two devices use one feedback id or one DJI command slot, or one
            device's command id is another one's feedback id; the message names both.
    """
    for family in families().values():
        if family.sim is not None and family.sim.check_channel is not None:
            family.sim.check_channel(devices)
    names: dict[str, SimDevice] = {}
    sent: dict[int, SimDevice] = {}
    for dev in devices:
        if dev.name in names:
            raise SimConfigError(f'two motors are named {dev.name!r}')
        names[dev.name] = dev
        for frame_id in dev.transmit_ids:
            if frame_id in sent:
                raise SimConfigError(
                    f'{dev.name} and {sent[frame_id].name} both send on id 0x{frame_id:03X}'
                )
            sent[frame_id] = dev
    listened: dict[int, SimDevice] = {}
    for dev in devices:
        for frame_id in dev.listen_ids:
            if frame_id in sent:
                raise SimConfigError(
                    f'{dev.name} listens on 0x{frame_id:03X}, where {sent[frame_id].name} sends'
                )
            other = listened.get(frame_id)
            # e.g. DJI ESCs share group frames by design (their family checks the slots)
            shared = dev.shares_command_frames and other is not None and other.shares_command_frames
            if other is not None and not shared:
                raise SimConfigError(
                    f'{dev.name} and {other.name} both take commands on 0x{frame_id:03X}'
                )
            listened[frame_id] = dev
