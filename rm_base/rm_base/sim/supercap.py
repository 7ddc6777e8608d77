"""The simulated super-capacitor controller: HKUST RM2024's frames, a capacitor's energy.

It sits, as the board does, between the referee's chassis output and the chassis' motors
(docs/PROTOCOLS.md §8): each tick it takes the motors' electrical power, draws from the
referee no more than the limit of the robot's last 0x061 frame, charges the capacitor with
what the chassis leaves (up to ``max_charge_w``) and gives the chassis the rest from the
capacitor (up to ``max_discharge_w``) while it holds energy. The referee measures what it
draws (``input_power_w``). It answers on 0x051 every tick with its error bits, the chassis
power, its limit and how full it is.

Without a command for ``command_timeout_s`` (or with enable off) the board passes the
chassis' power straight through (a simulated choice: the firmware's own behaviour then
was not found). Tests set ``errors`` (CapError bits) and ``online``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rm_base.config.schema import Schema, number
from rm_base.hardware.errors import ProtocolError
from rm_base.hardware.protocols import supercap as protocol
from rm_base.sim_devices.device import Frame, SimDevice
from rm_base.sim_devices.errors import SimConfigError

_NS_PER_S = 1_000_000_000

#: The world's ``supercap`` beside its ``channel`` (the bridge's ``sim.supercap``; the
#: channel is then ``supercap.bus``'s).
SUPERCAP_SIM_SCHEMA = Schema((
    number('capacity_j', 2000.0, unit='J', gt=0.0, description='energy of the full capacitor'),
    number('energy', 1.0, ge=0.0, le=1.0, description='how full it starts (a fraction)'),
    number('max_charge_w', 150.0, unit='W', ge=0.0,
           description='most power it charges with'),
    number('max_discharge_w', 300.0, unit='W', ge=0.0,
           description='most power the capacitor gives the chassis'),
    number('efficiency', 0.9, gt=0.0, le=1.0,
           description='of charging, and of discharging (each way)'),
    number('command_timeout_s', 0.1, unit='s', gt=0.0,
           description='no 0x061 this long: the chassis power passes straight through'),
))


class SimSupercap:
    """The board on one channel (see the module docstring).

    Args:
        channel: the channel it is on.
        chassis: the motors on its output (their electrical power is the chassis').
        values: ``SUPERCAP_SIM_SCHEMA``'s values.
    """

    name = 'supercap'

    def __init__(self, channel: str, chassis: Sequence[SimDevice],
                 values: Mapping[str, Any]) -> None:
        self.channel = channel
        self.capacity_j: float = values['capacity_j']
        self.energy_j: float = values['energy'] * self.capacity_j
        self.max_charge_w: float = values['max_charge_w']
        self.max_discharge_w: float = values['max_discharge_w']
        self.efficiency: float = values['efficiency']
        self.errors = 0
        self.online = True
        #: The robot's last command: (enable, limit [W], buffer [J], sim time [ns]).
        self.command: tuple[bool, int, int, int] | None = None
        self.commands = 0
        self.ignored = 0
        self.chassis_power_w = 0.0
        self.input_power_w = 0.0
        self._chassis = tuple(chassis)
        self._timeout_ns = round(values['command_timeout_s'] * _NS_PER_S)
        self._listen = frozenset({protocol.COMMAND_ID})

    @property
    def energy(self) -> float:
        """How full it is, 0..1."""
        return self.energy_j / self.capacity_j

    @property
    def listen_ids(self) -> frozenset[int]:
        """It reads 0x061."""
        return self._listen

    def receive(self, arbitration_id: int, data: bytes, now_ns: int, *,
                is_extended_id: bool = False, is_remote_frame: bool = False,
                is_fd: bool = False) -> list[Frame]:
        """Take the robot's 0x061; it never answers a frame (it streams)."""
        if not self.online or is_extended_id or is_remote_frame or is_fd:
            return []
        try:
            enable, _restart, limit, buffer = protocol.decode_command(bytes(data))
        except ProtocolError:
            self.ignored += 1
            return []
        self.command = (enable, limit, buffer, now_ns)
        self.commands += 1
        return []

    def step(self, now_ns: int, dt: float) -> None:
        """Move this tick's energy: the chassis' power against the referee's limit."""
        power = sum(d.model.electrical_power for d in self._chassis if d.powered)
        self.chassis_power_w = power
        command = self.command
        if (command is None or not command[0] or now_ns - command[3] > self._timeout_ns
                or not self.online or self.errors):
            self.input_power_w = max(0.0, power)
            return
        limit = min(max(command[1], protocol.MIN_LIMIT_W), protocol.MAX_LIMIT_W)
        if power <= limit:  # the chassis leaves some: charge with it
            room_w = (self.capacity_j - self.energy_j) / dt / self.efficiency
            charge = min(limit - power, self.max_charge_w, room_w)
            self.energy_j = min(self.capacity_j, self.energy_j + charge * self.efficiency * dt)
            self.input_power_w = max(0.0, power + charge)
        else:  # the chassis wants more: the capacitor gives what it has
            held_w = self.energy_j * self.efficiency / dt
            give = min(power - limit, self.max_discharge_w, held_w)
            self.energy_j = max(0.0, self.energy_j - give / self.efficiency * dt)
            self.input_power_w = power - give

    def emit(self, now_ns: int) -> list[Frame]:
        """The 0x051 frame, every tick (the board's 1 kHz)."""
        if not self.online:
            return []
        limit = self.command[1] if self.command is not None else 0
        data = protocol.encode_feedback(self.errors, self.chassis_power_w, limit,
                                        min(1.0, max(0.0, self.energy)))
        return [(protocol.FEEDBACK_ID, data)]


def supercap_from_config(config: Mapping[str, Any], chassis: Sequence[SimDevice]) -> SimSupercap:
    """Build the board from the world's ``supercap`` dict: ``channel`` and SUPERCAP_SIM_SCHEMA.

    Raises:
        SimConfigError: a missing, unknown or invalid key.
    """
    channel = config.get('channel')
    if not isinstance(channel, str) or not channel:
        raise SimConfigError(f'supercap.channel must name a channel, got {channel!r}')
    values = {k: v for k, v in config.items() if k != 'channel'}
    return SimSupercap(channel, chassis,
                       SUPERCAP_SIM_SCHEMA.read('supercap', values, SimConfigError))
