"""The simulated world of a bridge in sim mode, built from the bridge's own parameters.

One world for all buses: a channel per bus (its ``channel``, default the bus name), on it
one simulated motor per joint of that bus, named like the joint. The motor takes the
joint's type and id, and the protocol options both sides must agree on (DJI scales,
Damiao/Cheetah ``master_id``, ``limits``, ``model``). A joint with its own ``gear_ratio``
(an M3508 without its gearbox on a friction wheel) gets the same rotor behind that gear:
the simulator's output-shaft constants are rescaled by ``k = gear_ratio / default gear``
(torque and back-EMF constants and Coulomb friction by ``k``, viscous friction by
``k²``). ``joints.<joint>.sim.*`` overrides anything (physics such as ``load_inertia``,
driver settings such as ``overtemp_c``, or the simulated ``type``). ``sim.body`` and
``sim.imu`` become the world's ``body`` and its one IMU, ``sim.referee`` its referee,
``sim.remote`` its DR16 receiver, ``sim.image_link`` its image link.

Hardware types without a simulated model of their own (``dm4340``, ``dm10010l``, a
``damiao`` of another model) are simulated as the model that shares their protocol
(``dm4310`` or ``dm8009``) with their own MIT limits, unless ``joints.<joint>.sim.type``
says otherwise; a Piper joint cannot be simulated.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rm_base.bridge.errors import BridgeConfigError
from rm_base.bridge.params import SimSettings
from rm_base.hardware.config import HardwareConfig, JointConfig
from rm_base.motors import UnknownTypeError, families, family_of, sim_family, sim_types


def _simulated_joint_types() -> list[str]:
    return sorted(
        t for f in families().values() if f.sim is not None for t in f.sim.joint_types
    )


def motor_config(joint: JointConfig, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The simulated motor (``rm_base.sim.device_from_config`` dict) for one joint.

    Raises:
        BridgeConfigError: the joint's type is unknown, or has no simulated model and no
            ``sim.type``.
    """
    overrides = dict(overrides or {})
    try:
        family = family_of(joint.type)
    except UnknownTypeError as err:
        # the hardware layer's own message, before the simulator's would hide a typo
        raise BridgeConfigError(f'joints.{joint.name}.{err}') from None
    found = family.sim.simulated_type(joint) if family.sim is not None else None
    if found is not None:
        sim_type, extra = found
    elif 'type' in overrides:
        sim_type, extra = str(overrides['type']), {}
    else:
        raise BridgeConfigError(
            f'joints.{joint.name}.type {joint.type!r} has no simulated motor; simulated '
            f'types: {", ".join(_simulated_joint_types())} (or set joints.{joint.name}.sim.type)'
        )
    config: dict[str, Any] = {'type': sim_type, 'id': joint.id, 'name': joint.name, **extra}
    final_type = str(overrides.get('type', sim_type))
    try:
        sim = sim_family(final_type)
    except UnknownTypeError:
        raise BridgeConfigError(
            f'joints.{joint.name}.sim.type {final_type!r} is not a simulated motor; known: '
            f'{", ".join(sim_types())}'
        ) from None
    for key in sim.shared_options:
        if key in joint.options:
            value = joint.options[key]
            config[key] = dict(value) if isinstance(value, Mapping) else value
    if joint.gear_ratio is not None:
        config.update(regeared(final_type, joint.gear_ratio))
    config.update(overrides)
    return config


def regeared(sim_type: str, gear_ratio: float) -> dict[str, float]:
    """Output-shaft constants of a simulated motor type's rotor behind another gear.

    Args:
        sim_type: simulated motor type (``m3508``...).
        gear_ratio: rotor turns per output turn.

    Returns:
        ``gear_ratio`` and the rescaled ``torque_constant``, ``back_emf_constant``,
        ``coulomb_friction`` and ``viscous_friction`` (see the module docstring).

    Raises:
        BridgeConfigError: unknown simulated type.
    """
    try:
        base = sim_family(sim_type).models[sim_type]
    except UnknownTypeError:
        raise BridgeConfigError(
            f'unknown simulated motor type {sim_type!r}; known: {", ".join(sim_types())}'
        ) from None
    k = gear_ratio / base.gear_ratio
    return {
        'gear_ratio': gear_ratio,
        'torque_constant': base.torque_constant * k,
        'back_emf_constant': base.back_emf_constant * k,
        'coulomb_friction': base.coulomb_friction * k,
        'viscous_friction': base.viscous_friction * k * k,
    }


def world_config(hardware: HardwareConfig, sim: SimSettings) -> dict[str, Any]:
    """The world config (``rm_base.sim.SimWorld.from_config`` schema) of a sim-mode bridge.

    Args:
        hardware: the bridge's parsed hardware config.
        sim: the simulator settings from the parameters.

    Returns:
        A plain dict: timing, seed, channels, and body / imus / supercap / referee /
        target / remote / image_link if configured.

    Raises:
        BridgeConfigError: a joint has no simulated model, or two buses share a channel.
    """
    channels: dict[str, list[dict[str, Any]]] = {}
    channel_of_bus: dict[str, str] = {}
    for bus in hardware.buses:
        name = str(bus.channel)
        if name in channels:
            other = next(b for b, c in channel_of_bus.items() if c == name)
            raise BridgeConfigError(
                f'buses.{bus.name}.channel and buses.{other}.channel are both {name!r}; '
                'in sim mode every bus needs a channel of its own'
            )
        channels[name] = []
        channel_of_bus[bus.name] = name
    for joint in hardware.joints:
        channels[channel_of_bus[joint.bus]].append(motor_config(joint, sim.motors.get(joint.name)))
    config: dict[str, Any] = {
        'timing': sim.timing.value,
        'seed': sim.seed,
        'channels': channels,
    }
    if sim.body:
        config['body'] = dict(sim.body)
    if sim.imu is not None:
        config['imus'] = [dict(sim.imu)]
    if hardware.supercap is not None:  # simulated as the motors are: always, defaults or not
        if 'channel' in sim.supercap:
            raise BridgeConfigError('sim.supercap.channel: the board is on supercap.bus')
        config['supercap'] = {**sim.supercap, 'channel': channel_of_bus[hardware.supercap.bus]}
    elif sim.supercap:
        raise BridgeConfigError('sim.supercap.* is set, but there is no supercap.bus')
    if sim.referee is not None:
        config['referee'] = dict(sim.referee)
    if sim.target is not None:
        config['target'] = dict(sim.target)
    if sim.remote is not None:
        config['remote'] = dict(sim.remote)
    if sim.image_link is not None:
        config['image_link'] = dict(sim.image_link)
    return config
