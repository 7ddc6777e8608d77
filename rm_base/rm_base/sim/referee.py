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

from rm_base.hardware.protocols.referee import (
    GameProgress,
    GameStatus,
    ProtocolVersion,
    encode_frame,
    encode_status,
)
from rm_base.sim.devices import SimDevice
from rm_base.sim.errors import SimConfigError
from rm_base.sim.joint import check_keys, config_number
from rm_base.sim.launcher import Launcher, Shot
from rm_base.sim.pty_port import PtyPort
from rm_base.sim.referee_rules import STEP_NS, Outputs, RefereeRules, RefereeSettings

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

    def tick(self, now_ns: int, dt: float, shots: Sequence[Shot]) -> list[bytes]:
        """Account one physics tick ending at now_ns; the frames due now.

        Called by the world after the motors stepped, with the projectiles of this tick.
        """
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


_SETTINGS = {
    'robot_id': 'robot_id',
    'level': 'level',
    'max_hp': 'max_hp',
    'heat_limit': 'heat_limit',
    'cooling': 'cooling_per_s',
    'allowance': 'allowance',
}
_FLOATS = {
    'chassis_power_limit': 'chassis_power_limit_w',
    'buffer_max': 'buffer_max_j',
    'chassis_cut': 'chassis_cut_s',
}
_KEYS = {'path', 'name', 'protocol_version', 'calibre', 'match_s', *_SETTINGS, *_FLOATS}


def referee_from_config(
    config: Mapping[str, Any],
    *,
    chassis: Sequence[SimDevice],
    gimbal: Sequence[SimDevice],
    launcher: Launcher | None,
) -> SimReferee:
    """Build the referee from a plain dict (the world's ``referee``; bridge ``sim.referee``).

    Keys: ``path`` (required), ``name`` ('referee'), ``protocol_version`` (2026; 2024 or
    2025), ``robot_id`` (3), ``level`` (1), ``max_hp`` (200), ``heat_limit`` (100),
    ``cooling`` [1/s] (10), ``chassis_power_limit`` [W] (60), ``buffer_max`` [J] (60),
    ``chassis_cut`` [s] (5), ``calibre`` (the launcher's, else 17), ``allowance`` (500),
    ``match_s`` (420).

    Raises:
        SimConfigError: a missing, unknown or invalid key.
    """
    check_keys(config, _KEYS, 'referee')
    if not isinstance(config.get('path'), str):
        raise SimConfigError(f'referee needs a path (string), got {config.get("path")!r}')
    try:
        version = ProtocolVersion(str(config.get('protocol_version', 2026)))
    except ValueError:
        raise SimConfigError(
            f'referee protocol_version must be 2024, 2025 or 2026, got '
            f'{config["protocol_version"]!r}'
        ) from None
    kwargs: dict[str, Any] = {
        field: config[key] for key, field in _SETTINGS.items() if key in config
    }
    kwargs.update(
        {field: config_number(config, key, 'referee') for key, field in _FLOATS.items()
         if key in config}
    )
    calibre = config.get('calibre', launcher.calibre if launcher is not None else 17)
    if launcher is not None and calibre != launcher.calibre:
        raise SimConfigError(
            f"referee calibre {calibre!r} is not the shooter's ({launcher.calibre} mm)"
        )
    match_s = config.get('match_s', 420)
    if isinstance(match_s, bool) or not isinstance(match_s, int) or match_s < 0:
        raise SimConfigError(f'referee match_s must be an integer >= 0, got {match_s!r}')
    return SimReferee(
        RefereeSettings(version=version, calibre=calibre, **kwargs),
        path=config['path'],
        chassis=chassis,
        gimbal=gimbal,
        launcher=launcher,
        match_s=match_s,
        name=str(config.get('name', 'referee')),
    )
