"""What the referee did to the robot's power, said once per change.

The referee's robot status (0x0201, 10 Hz) carries the HP and which 24 V outputs are on.
When HP reaches 0 every output goes off and the motors behind them stop answering; when a
rule cuts the chassis or locks the launcher one output goes off. Seen from the motors alone
that is "offline" with no reason, so the plugin says the reason once, when it changes.
"""

from __future__ import annotations

from dataclasses import dataclass

from rm_base.hardware.protocols.referee import RobotStatus

_OUTPUTS = ('gimbal', 'chassis', 'shooter')


@dataclass(frozen=True)
class _Seen:
    destroyed: bool
    off: tuple[str, ...]


def _seen(status: RobotStatus) -> _Seen:
    on = (status.gimbal_power, status.chassis_power, status.shooter_power)
    return _Seen(status.hp <= 0, tuple(n for n, up in zip(_OUTPUTS, on, strict=True) if not up))


class PowerWatch:
    """Turns each robot status into a message when what the referee did changed.

    The first status says something only if an output is already off.
    """

    def __init__(self) -> None:
        self._last: _Seen | None = None

    def note(self, status: RobotStatus) -> str | None:
        """The message this status calls for, or None if nothing changed."""
        now, last = _seen(status), self._last
        self._last = now
        if last is None:
            last = _Seen(False, ())
        if now == last:
            return None
        if now.destroyed and not last.destroyed:
            return (f'referee: robot destroyed (HP 0 of {status.max_hp}): every power output '
                    'off until a revival')
        if last.destroyed and not now.destroyed:
            return f'referee: robot revived (HP {status.hp} of {status.max_hp})'
        cut = [n for n in now.off if n not in last.off]
        back = [n for n in last.off if n not in now.off]
        said = []
        if cut:
            said.append(f'power off at {", ".join(cut)} (a rule: chassis power or barrel heat)')
        if back:
            said.append(f'power back at {", ".join(back)}')
        return 'referee: ' + '; '.join(said) if said else None
