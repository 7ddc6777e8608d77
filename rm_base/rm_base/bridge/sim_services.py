"""Fault injection services of a simulated world (std_srvs/SetBool; true injects, false clears).

``<prefix><joint>/offline``, ``.../jam``, ``.../over_temperature``, ``.../garbage`` per
joint and ``<prefix><bus>/bus_off`` per bus: a locked rotor, 130 °C, 100 random frames/s
on the feedback id, a bus in bus-off. ``<prefix>referee/reset`` (std_srvs/Trigger, when the
world has a referee) revives the robot as a referee's revival does: full HP, a cold barrel,
a full buffer, every output on. Served by can_bridge when it runs rm_sim in-process
(prefix ``~/sim/``) and by the rm_sim process (prefix ``~/``).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import can
from std_srvs.srv import SetBool, Trigger

from rm_base.sim import Fault, FaultKind, SimError, SimWorld
from rm_base.sim.referee import SimReferee

#: Faults the services inject, by service name, with the parameters they use.
SIM_FAULTS: dict[str, Callable[[], Fault]] = {
    FaultKind.OFFLINE.value: Fault.offline,
    FaultKind.JAM.value: Fault.jam,
    FaultKind.OVER_TEMPERATURE.value: Fault.over_temperature,
    FaultKind.GARBAGE.value: Fault.garbage,
}

# A joint or bus name becomes one token of a service name.
_NAME_TOKEN = re.compile(r'[A-Za-z][A-Za-z0-9_]*')


class SimFaultServices:
    """The fault services of world on node (see the module docstring).

    Args:
        node: the node that serves them.
        world: the simulated world.
        joints: joint (simulated motor) names.
        buses: bus name -> its simulated channel name.
        prefix: service name prefix (``~/sim/`` or ``~/``).
    """

    def __init__(
        self,
        node: Any,
        world: SimWorld,
        joints: Iterable[str],
        buses: Mapping[str, str],
        *,
        prefix: str,
    ) -> None:
        self._node = node
        self._world = world
        self.services = []
        for joint in joints:
            if not _NAME_TOKEN.fullmatch(joint):
                node.get_logger().warning(
                    f'joint {joint!r} is not a valid ROS name token: no fault services'
                )
                continue
            for kind in SIM_FAULTS:
                self.services.append(
                    node.create_service(
                        SetBool, f'{prefix}{joint}/{kind}',
                        functools.partial(self._on_fault, joint, kind),
                    )
                )
        for bus, channel in buses.items():
            if _NAME_TOKEN.fullmatch(bus):
                self.services.append(
                    node.create_service(
                        SetBool, f'{prefix}{bus}/bus_off',
                        functools.partial(self._on_bus_off, bus, channel),
                    )
                )
        if world.referee is not None:
            self.services.append(
                node.create_service(
                    Trigger, f'{prefix}referee/reset',
                    functools.partial(self._on_referee_reset, world.referee),
                )
            )

    def _on_fault(
        self, joint: str, kind: str, request: SetBool.Request, response: SetBool.Response
    ) -> SetBool.Response:
        try:
            if request.data:
                self._world.inject(joint, SIM_FAULTS[kind]())
            else:
                self._world.clear_faults(joint, kind)
        except SimError as err:
            response.success, response.message = False, str(err)
            return response
        response.success = True
        response.message = f'{joint}: {kind} {"injected" if request.data else "cleared"}'
        self._node.get_logger().info(f'sim: {response.message}')
        return response

    def _on_bus_off(
        self, bus: str, channel: str, request: SetBool.Request, response: SetBool.Response
    ) -> SetBool.Response:
        state = can.BusState.ERROR if request.data else can.BusState.ACTIVE
        try:
            self._world.channel(channel).set_state(state)
        except SimError as err:
            response.success, response.message = False, str(err)
            return response
        response.success = True
        response.message = f'{bus}: {"bus-off injected" if request.data else "bus-off cleared"}'
        self._node.get_logger().info(f'sim: {response.message}')
        return response

    def _on_referee_reset(
        self, referee: SimReferee, _request: Trigger.Request, response: Trigger.Response
    ) -> Trigger.Response:
        with self._world.lock:  # the physics thread switches the outputs too
            hp_before = referee.rules.hp
            referee.revive()
        response.success = True
        response.message = (
            f'referee: robot revived (HP {hp_before} -> {referee.rules.hp}, every output on)'
        )
        self._node.get_logger().info(f'sim: {response.message}')
        return response
