"""A simulated referee system on a pseudo-terminal, judging the simulated robot.

It measures what the real one measures: the chassis output's power (the wheel motors'
electrical power, summed each tick and averaged over the 100 ms rule period; a chassis
braking back into the supply counts as 0 W, never as a refill) and every projectile the
launcher fires (rm_base.sim.launcher). It applies the game rules
(rm_base.sim.referee_rules) and switches its outputs as the power-management module does:
a cut chassis or a locked launcher loses the power of its motors, which stop answering
on CAN and coast.

It sends, in the configured season's layouts (docs/PROTOCOLS.md §6.2): game status
(0x0001) at 1 Hz; robot status (0x0201), power and heat (0x0202) and projectile allowance
(0x0208) at 10 Hz, right after each rule step; shoot data (0x0207) after every projectile;
hurt (0x0206) when a rule costs HP. :meth:`SimReferee.unplug` stops its frames (a pulled
cable) while it goes on judging.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rm_base.config.schema import Schema, integer, number, one_of, string
from rm_base.hardware.protocols.referee import (
    INTERACTION_CMD_ID,
    FrameParser,
    GameProgress,
    GameStatus,
    ProtocolVersion,
    encode_frame,
    encode_status,
)
from rm_base.sim.launcher import Launcher, Shot
from rm_base.sim.pty_port import PtyPort
from rm_base.sim.referee_client import SimClient
from rm_base.sim.referee_rules import STEP_NS, Outputs, RefereeRules, RefereeSettings
from rm_base.sim.supercap import SimSupercap
from rm_base.sim_devices.device import SimDevice
from rm_base.sim_devices.errors import SimConfigError

_NS_PER_S = 1_000_000_000
_GAME_STATUS_EVERY = 10  # rule steps: 1 Hz
_RMUC = 1


class SimReferee:
    """The referee system of one simulated robot (see the module docstring).

    Attributes:
        rules: the robot's state as the referee keeps it.
        port: the simulated serial port the referee plugin opens.
        plugged: False while the cable is pulled (no frames sent).
    """

    def __init__(
        self,
        settings: RefereeSettings,
        *,
        path: str,
        chassis: Sequence[SimDevice] = (),
        gimbal: Sequence[SimDevice] = (),
        launcher: Launcher | None = None,
        match_s: int = 420,
        unix_time: int = 1_700_000_000,
        name: str = 'referee',
    ) -> None:
        """Open the terminal.

        Args:
            settings: the limits the referee sets and the season.
            path: where the terminal's symlink goes (``${VAR}`` expanded).
            chassis: the motors on the chassis output (their power is measured).
            gimbal: the motors on the gimbal output.
            launcher: the shooter (its motors are on the shooter output), or None.
            match_s: length of the match the game status counts down [s].
            unix_time: the game status's clock at time 0 [s].
            name: for messages.

        Raises:
            SimConfigError: the terminal cannot be created.
        """
        self.name = name
        self.rules = RefereeRules(settings)
        self.launcher = launcher
        self.plugged = True
        #: A super-capacitor board between the chassis output and the wheels, if any
        #: (rm_base.sim.supercap): the referee then measures its input.
        self.supply: SimSupercap | None = None
        self._ports: dict[str, tuple[SimDevice, ...]] = {
            'chassis': tuple(chassis),
            'gimbal': tuple(gimbal),
            'shooter': launcher.devices if launcher is not None else (),
        }
        self._match_ns = match_s * _NS_PER_S
        self._unix_time = unix_time
        self._energy_j = 0.0
        self._steps = 0
        self._next_step_ns = STEP_NS
        self._seq = 0
        self._outputs = Outputs()
        #: The robot's operator client, drawn on through 0x0301 (rm_base.sim.referee_client).
        self.client = SimClient(settings.robot_id)
        self._parser = FrameParser()
        self.port = PtyPort(path, name)

    @property
    def version(self) -> ProtocolVersion:
        """The season the referee speaks."""
        return self.rules.settings.version

    def unplug(self) -> None:
        """Pull the cable: no more frames (the rules still run)."""
        self.plugged = False

    def plug(self) -> None:
        """Plug the cable back in."""
        self.plugged = True

    def revive(self) -> None:
        """Revive the robot (:meth:`RefereeRules.revive`); its outputs are on again at once.

        Call it with the world's lock held (the physics thread switches the outputs too).
        """
        self.rules.revive()
        self._switch_outputs()

    def receive(self, data: bytes, now_ns: int) -> None:
        """Bytes the robot sent: its 0x0301 frames go to the client; others are ignored."""
        for frame in self._parser.feed(data):
            if frame.cmd_id == INTERACTION_CMD_ID:
                self.client.on_frame(frame, now_ns)

    def tick(self, now_ns: int, dt: float, shots: Sequence[Shot]) -> list[bytes]:
        """Account one physics tick ending at now_ns; the frames due now.

        Called by the world after the motors stepped, with the projectiles of this tick.
        What the robot wrote on the terminal is read first.
        """
        if self.plugged:
            sent = self.port.read()
            if sent:
                self.receive(sent, now_ns)
        supply = self.supply
        if supply is not None:  # a super-capacitor board: what it draws
            power = supply.input_power_w
        else:
            power = 0.0
            for device in self._ports['chassis']:
                if device.powered:
                    power += device.model.electrical_power
        self._energy_j += max(0.0, power) * dt
        if not shots and now_ns < self._next_step_ns:
            return []  # most ticks: the rules (and so the outputs) only change on these
        records: list[Any] = [self.rules.shot(shot.time_ns, shot.speed_mps) for shot in shots]
        if now_ns >= self._next_step_ns:
            period_s = (now_ns - self._next_step_ns + STEP_NS) / _NS_PER_S
            records += self.rules.step(now_ns, self._energy_j / period_s)
            self._energy_j = 0.0
            self._next_step_ns += STEP_NS
            if self._steps % _GAME_STATUS_EVERY == 0:
                records.append(self._game_status(now_ns))
            self._steps += 1
            records += [
                self.rules.robot_status(),
                self.rules.power_heat(),
                self.rules.projectile_allowance(),
            ]
        self._switch_outputs()
        if not self.plugged:
            return []
        return [self._frame(record) for record in records]

    def write(self, frame: bytes) -> None:
        """Write a frame to the terminal."""
        self.port.write(frame)

    def close(self) -> None:
        """Close the terminal (idempotent)."""
        self.port.close()

    def _game_status(self, now_ns: int) -> GameStatus:
        remaining = max(0, self._match_ns - now_ns) // _NS_PER_S
        return GameStatus(
            _RMUC, GameProgress.IN_MATCH, remaining, self._unix_time + now_ns // _NS_PER_S
        )

    def _frame(self, record: Any) -> bytes:
        frame = encode_frame(*encode_status(record, self.version), seq=self._seq)
        self._seq = (self._seq + 1) & 0xFF
        return frame

    def _switch_outputs(self) -> None:
        outputs = self.rules.outputs
        if outputs == self._outputs:
            return
        for port in ('chassis', 'gimbal', 'shooter'):
            on = getattr(outputs, port)
            if on != getattr(self._outputs, port):
                for device in self._ports[port]:
                    device.set_powered(on)
        self._outputs = outputs


#: ``sim.referee``: the simulated referee system (its settings: ``RefereeSettings``).
REFEREE_SCHEMA = Schema((
    string('path', nonempty=True,
           description="the pty's link, e.g. /tmp/rm_sim_${ROS_DOMAIN_ID}/referee "
           '(${VAR} expanded)'),
    string('name', 'referee', description='name in logs'),
    one_of('protocol_version', (2024, 2025, 2026), 2026,
           description='the season whose rules and frame layouts it plays'),
    integer('robot_id', 3, ge=1, le=0xFF, description='1 hero, 3-5 infantry, 7 sentry... '
            '(blue = red + 100)'),
    integer('level', 1, ge=0, le=0xFFFF, description='robot level'),
    integer('max_hp', 200, ge=1, le=0xFFFF, description='HP at the start'),
    integer('heat_limit', 100, ge=0, le=0xFFFF, description='barrel heat limit'),
    integer('cooling', 10, unit='1/s', ge=0, le=0xFFFF, description='barrel cooling value'),
    number('chassis_power_limit', 60.0, unit='W', ge=0.0, description='chassis power limit'),
    number('buffer_max', 60.0, unit='J', ge=0.0, description='buffer energy cap'),
    number('chassis_cut', 5.0, unit='s', ge=0.0,
           description='how long an empty buffer cuts the chassis (2025 on)'),
    one_of('calibre', (17, 42), None, description="projectile calibre [mm]; default: the "
           "shooter's, else 17"),
    integer('allowance', 500, ge=0, le=0xFFFF, description='projectiles the robot may fire'),
    integer('match_s', 420, unit='s', ge=0, description='match length'),
))


def referee_from_config(
    config: Mapping[str, Any],
    *,
    chassis: Sequence[SimDevice],
    gimbal: Sequence[SimDevice],
    launcher: Launcher | None,
) -> SimReferee:
    """Build the referee from a plain dict (the world's ``referee``; bridge ``sim.referee``).

    Keys: ``REFEREE_SCHEMA``.

    Raises:
        SimConfigError: a missing, unknown or invalid key.
    """
    values = REFEREE_SCHEMA.read('referee', config, SimConfigError)
    calibre = values['calibre']
    if calibre is None:
        calibre = launcher.calibre if launcher is not None else 17
    if launcher is not None and calibre != launcher.calibre:
        raise SimConfigError(
            f"referee calibre {calibre!r} is not the shooter's ({launcher.calibre} mm)"
        )
    settings = RefereeSettings(
        version=ProtocolVersion(str(values['protocol_version'])),
        robot_id=values['robot_id'],
        level=values['level'],
        max_hp=values['max_hp'],
        heat_limit=values['heat_limit'],
        cooling_per_s=values['cooling'],
        chassis_power_limit_w=values['chassis_power_limit'],
        buffer_max_j=values['buffer_max'],
        calibre=calibre,
        allowance=values['allowance'],
        chassis_cut_s=values['chassis_cut'],
    )
    return SimReferee(
        settings,
        path=values['path'],
        chassis=chassis,
        gimbal=gimbal,
        launcher=launcher,
        match_s=values['match_s'],
        name=values['name'],
    )
