"""Command groups: the owners of frames that several motors share.

DJI ESCs take one command frame per four motors (0x200, 0x1FF, 0x2FF, 0x1FE, 0x2FE).
A :class:`DjiCommandGroup` owns one such frame on one bus; its motors only hold their raw
target (``command_raw``, computed in ``update()``), and the group packs the frame once
per tick. A slot without a motor is sent as 0.
"""

from __future__ import annotations

from collections.abc import Iterable

import can

from rm_base.hardware.errors import HardwareConfigError
from rm_base.motors.dji import protocol as dji
from rm_base.motors.dji.actuator import DjiActuator


class DjiCommandGroup:
    """One shared DJI command frame on one bus."""

    def __init__(self, bus_name: str, arbitration_id: int) -> None:
        """Create an empty group.

        Args:
            bus_name: bus the frame is sent on.
            arbitration_id: the frame id (0x200, 0x1FF, 0x2FF, 0x1FE or 0x2FE).

        Raises:
            HardwareConfigError: not a DJI command id.
        """
        if arbitration_id not in dji.COMMAND_IDS:
            raise HardwareConfigError(f'0x{arbitration_id:03X} is not a DJI command frame id')
        self.bus_name = bus_name
        self.arbitration_id = arbitration_id
        self.members: list[DjiActuator | None] = [None] * dji.SLOTS_PER_FRAME

    def add(self, actuator: DjiActuator) -> None:
        """Put ``actuator`` into its slot.

        Raises:
            HardwareConfigError: wrong frame or bus, or the slot is taken.
        """
        if actuator.command_frame_id != self.arbitration_id or actuator.bus_name != self.bus_name:
            raise HardwareConfigError(
                f'{actuator.name} (0x{actuator.command_frame_id:03X} on {actuator.bus_name}) '
                f'does not belong to group 0x{self.arbitration_id:03X} on {self.bus_name}'
            )
        other = self.members[actuator.slot]
        if other is not None:
            raise HardwareConfigError(
                f'{actuator.name} and {other.name} share frame 0x{self.arbitration_id:03X} '
                f'slot {actuator.slot} on {self.bus_name}'
            )
        self.members[actuator.slot] = actuator

    @property
    def name(self) -> str:
        """Readable name, e.g. ``can0/0x200``."""
        return f'{self.bus_name}/0x{self.arbitration_id:03X}'

    def pack_command(self) -> can.Message:
        """The shared frame with every member's raw command (0 for empty slots)."""
        m = self.members
        raws = [0 if a is None else a.command_raw for a in m]
        return can.Message(
            arbitration_id=self.arbitration_id,
            data=dji.pack_command(raws),
            is_extended_id=False,
        )


def build_dji_groups(actuators: Iterable[DjiActuator]) -> list[DjiCommandGroup]:
    """Group DJI actuators by (bus, command frame), checking slot/feedback collisions.

    Raises:
        HardwareConfigError: two motors on one bus collide (shared slot or feedback id).
    """
    by_bus: dict[str, list[DjiActuator]] = {}
    for a in actuators:
        by_bus.setdefault(a.bus_name, []).append(a)
    groups: dict[tuple[str, int], DjiCommandGroup] = {}
    for bus, members in by_bus.items():
        try:
            dji.check_collisions(
                [(a.kind, a.config.id) for a in members], names=[a.name for a in members]
            )
        except HardwareConfigError as err:
            raise HardwareConfigError(f'bus {bus}: {err}') from err
        for a in members:
            key = (bus, a.command_frame_id)
            if key not in groups:
                groups[key] = DjiCommandGroup(bus, a.command_frame_id)
            groups[key].add(a)
    return list(groups.values())
