"""Power limits rm_robot asks for over DDS (/power_limit), run in the bridge's loop.

In one process the chassis hands its power stage to the loop itself; with rm_robot in a
process of its own it sends the stage's joints, power model and limit on /power_limit, and
the bridge runs the same stage after its wheels' 1 kHz speed loops (a wheel loop closed
over DDS at the plugin's rate oscillates). A message that names an unknown joint or holds
a negative or non-finite coefficient is rejected whole and logged; the stage as it was
stays.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from typing import Any, NamedTuple

from rm_base.bridge.errors import PowerLimitRejectedError
from rm_base.control import ChassisPowerModel
from rm_base.errors import ConfigError, InputRejectedError
from rm_base.hardware import CanHardware
from rm_base.hardware.supercap import PowerSupply


class PowerLimitRequest(NamedTuple):
    """One checked /power_limit message."""

    group: str
    joints: tuple[str, ...]
    model: ChassisPowerModel
    limit_w: float
    supply: PowerSupply


def parse_power_limit(msg: Any, known_joints: Collection[str]) -> PowerLimitRequest:
    """Check one rm_msgs/PowerLimit.

    Raises:
        PowerLimitRejectedError: no group, no joint, an unknown or repeated joint, a bad
            coefficient or limit (the message says which).
    """
    group = str(msg.group)
    joints = tuple(str(j) for j in msg.joints)
    if not group:
        raise PowerLimitRejectedError('power limit without a group name')
    if not joints or len(set(joints)) != len(joints):
        raise PowerLimitRejectedError(
            f'power limit {group!r}: joints {list(joints)} (none, or one twice)'
        )
    unknown = [j for j in joints if j not in known_joints]
    if unknown:
        raise PowerLimitRejectedError(f'power limit {group!r}: unknown joint(s) {unknown}')
    try:
        model = ChassisPowerModel(float(msg.k1), float(msg.k2), float(msg.static_power_w))
    except ConfigError as err:
        raise PowerLimitRejectedError(f'power limit {group!r}: {err}') from err
    limit = float(msg.limit_w)
    if math.isnan(limit) or limit < 0.0:
        raise PowerLimitRejectedError(f'power limit {group!r}: limit_w {limit} (must be >= 0)')
    try:
        supply = PowerSupply(float(msg.referee_limit_w), float(msg.buffer_j),
                             float(msg.request_w))
    except InputRejectedError as err:
        raise PowerLimitRejectedError(f'power limit {group!r}: {err}') from err
    return PowerLimitRequest(group, joints, model, limit, supply)


class RemotePowerLimits:
    """The stages of the /power_limit requests, in the hardware's loop."""

    def __init__(self, hardware: CanHardware) -> None:
        self._hardware = hardware
        self._requests: dict[str, PowerLimitRequest] = {}

    def apply(self, request: PowerLimitRequest) -> None:
        """Add the group's stage, or change its limit (a new joint set or model: a new stage).

        Raises:
            PowerLimitRejectedError: the group's stage cannot join the loop (a group of
                that name that is not a /power_limit one, e.g. a plugin's own in this
                process); the loop stays as it was.
        """
        old = self._requests.get(request.group)
        if old is None and request.group in self._hardware.power_limits:
            raise PowerLimitRejectedError(
                f'power limit {request.group!r}: the loop has a stage of that group already'
            )
        if old is None or (old.joints, old.model) != (request.joints, request.model):
            if old is not None:
                self._hardware.remove_power_limit(request.group)
            self._hardware.add_power_limit(request.group, request.joints, request.model)
        stage = self._hardware.power_limits[request.group]
        stage.limit_w, stage.supply = request.limit_w, request.supply
        self._requests[request.group] = request
