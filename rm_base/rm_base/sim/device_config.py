"""Simulated motors from plain config dicts, and the check that they can share a bus.

The keys every motor has and its physics are read here; the rest belong to the motor's
family, which declares them (``SimFamily.schema``) and builds the device
(``rm_base.motors``: one registry of families).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.config.schema import Schema, integer, number, string
from rm_base.hardware.errors import HardwareConfigError, ValueRangeError
from rm_base.motors import DeviceParts, UnknownTypeError, families, sim_family
from rm_base.sim_devices.device import STD_ID_MAX, SimDevice
from rm_base.sim_devices.errors import SimConfigError
from rm_base.sim_devices.motor import MotorModel
from rm_base.sim_devices.motor_params import PHYSICS_SCHEMA

#: The keys every simulated motor has; its physics (PHYSICS_SCHEMA) and its family's
#: keys (``SimFamily.schema``) complete them.
MOTOR_SCHEMA = Schema(
    (
        string('type', nonempty=True,
               description='simulated motor type (m3508, m2006, gm6020, dm4310, dm8009, '
               'cheetah, mf9025, mg4010)'),
        integer('id', ge=0, le=STD_ID_MAX,
                description='ESC id (DJI) or CAN id'),
        string('name', None, nonempty=True,
               description="unique name; default '<type>_<id>'"),
        number('initial_position', 0.0, unit='rad', description='output angle at the start'),
        number('initial_velocity', 0.0, unit='rad/s', description='output speed at the start'),
        number('overtemp_c', None, unit='degC',
               description='the driver cuts its output above this winding temperature; '
               "default the family's (none for DJI and Cheetah, 120 for Damiao and LK)"),
    ),
    open=True,
)


def device_from_config(config: Mapping[str, Any], *, seed: int = 0) -> SimDevice:
    """Build a simulated motor from a plain dict.

    Keys: :data:`MOTOR_SCHEMA`, :data:`~rm_base.sim_devices.motor_params.PHYSICS_SCHEMA` (each
    defaulting to the type's model) and the family's ``SimFamily.schema``
    (docs/PARAMETERS.md lists them all).

    Args:
        config: the motor's dict.
        seed: seed of the device's random generator (garbage frames).

    Returns:
        The device.

    Raises:
        SimConfigError: a missing, unknown or invalid key, named as ``<motor>.<key>``.
    """
    named = config.get('name') if isinstance(config, Mapping) else None
    values = MOTOR_SCHEMA.read(named if isinstance(named, str) and named else 'motor', config,
                               SimConfigError)
    sim_type = values['type']
    try:
        family = sim_family(sim_type)
    except UnknownTypeError as err:
        raise SimConfigError(str(err)) from None
    name = values['name'] or f'{sim_type}_{values["id"]}'
    rest = MOTOR_SCHEMA.extras(config)
    allowed = PHYSICS_SCHEMA.names | family.schema.names
    unknown = sorted(set(rest) - allowed)
    if unknown:
        known = sorted(MOTOR_SCHEMA.names | allowed)
        raise SimConfigError(f'{name}: unknown key(s) {unknown}; known: {known}')
    physics = PHYSICS_SCHEMA.read(
        name, {k: v for k, v in rest.items() if k in PHYSICS_SCHEMA.names}, SimConfigError
    )
    options = family.schema.read(
        name, {k: v for k, v in rest.items() if k in family.schema.names}, SimConfigError
    )
    params = family.models[sim_type].replace(
        **{k: v for k, v in physics.items() if v is not None}
    )
    model = MotorModel(
        params, angle=values['initial_position'], velocity=values['initial_velocity']
    )
    common: dict[str, Any] = {'seed': seed}
    if values['overtemp_c'] is not None:
        common['overtemp_c'] = values['overtemp_c']
    try:
        return family.build(options, DeviceParts(name, sim_type, values['id'], model, common))
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
            # (a device may answer on the id it is asked on, as LK motors do)
            if frame_id in sent and sent[frame_id] is not dev:
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
