"""A terminal keyboard as the operator's hands: the bytes typed -> what is held, by time.

A terminal reports presses, never releases: a held key arrives once, then (after the
keyboard's repeat delay, 250-660 ms) again every 30-40 ms. So a key counts as held from
its first byte for :data:`FIRST_HOLD_S` (longer than any repeat delay), and once it
repeats, until :data:`REPEAT_HOLD_S` after its last byte: a tap is a short press, a held
key stays held, and a release shows within 0.2 s.

Letters are the DR16 keyboard's keys (docs/PROTOCOLS.md §5): an upper-case letter holds
SHIFT with it, a control character (Ctrl+letter) CTRL. The terminal has no mouse, so Q/E
and the arrows stand in for it: Q/E and left/right move it sideways, up/down up and down;
space is its left button. P toggles PASSIVE (the right switch down, and back up). Pure:
no terminal, no rclpy.
"""

from __future__ import annotations

import string
from dataclasses import dataclass

from rm_base.hardware.protocols.dbus import Key

#: A key's first byte holds it this long [s]: longer than any keyboard's repeat delay.
FIRST_HOLD_S = 0.7
#: A repeating key is held until this long after its last byte [s] (repeats come 30-40 ms).
REPEAT_HOLD_S = 0.2
#: Mouse speed [counts per frame] while a stand-in key is held (rm_manual's default
#: mouse_yaw, 0.02 rad/s per count: 100 counts turn the gimbal at 2 rad/s).
MOUSE_COUNTS = 100

# the mouse's stand-ins: name -> (x, y) direction
_MOUSE = {
    'Q': (-1, 0), 'E': (1, 0), 'LEFT': (-1, 0), 'RIGHT': (1, 0), 'UP': (0, -1), 'DOWN': (0, 1),
}
_ARROWS = {'A': 'UP', 'B': 'DOWN', 'C': 'RIGHT', 'D': 'LEFT'}
_LETTERS = frozenset(name for name in Key.__members__ if len(name) == 1) - {'Q', 'E'}
_FIRE = 'SPACE'
_PASSIVE = 'P'


@dataclass(frozen=True)
class Hands:
    """What the operator holds at one instant.

    Attributes:
        keys: DR16 keyboard bitmap (rm_base.hardware.protocols.dbus.Key).
        mouse_x, mouse_y: mouse speed [counts per frame], x > 0 right, y > 0 down.
        mouse_left: the left button held.
        passive: the right switch is down (everything PASSIVE).
        held: the names of the terminal keys held, for the screen.
    """

    keys: int = 0
    mouse_x: int = 0
    mouse_y: int = 0
    mouse_left: bool = False
    passive: bool = False
    held: tuple[str, ...] = ()


@dataclass
class _Press:
    first: float  # time of the first byte [s]
    last: float  # time of the last byte [s]
    modifiers: int  # SHIFT / CTRL bits that came with it

    def held(self, now: float) -> bool:
        repeated = self.last > self.first
        return now <= (self.last + REPEAT_HOLD_S if repeated else self.first + FIRST_HOLD_S)


class TerminalKeys:
    """Bytes from a terminal in cbreak mode -> :class:`Hands` (see the module docstring)."""

    def __init__(self) -> None:
        self._presses: dict[str, _Press] = {}
        self._pending = b''  # an escape sequence split between two reads
        self.passive = False
        self.ignored = 0  # bytes that are no key of ours

    def feed(self, data: bytes, now: float) -> None:
        """The bytes read at now [s] (monotonic)."""
        data, self._pending = self._pending + data, b''
        i = 0
        while i < len(data):
            byte = data[i]
            if byte == 0x1B:  # ESC [ A..D (or ESC O A..D): an arrow
                sequence = data[i:i + 3]
                if sequence in (b'\x1b', b'\x1b[', b'\x1bO'):  # the rest comes next read
                    self._pending = sequence
                    return
                arrow = (_ARROWS.get(chr(sequence[2]))
                         if len(sequence) == 3 and sequence[1:2] in (b'[', b'O') else None)
                if arrow is None:
                    self.ignored += 1
                    i += 1
                    continue
                self._press(arrow, 0, now)
                i += 3
                continue
            self._byte(byte, now)
            i += 1

    def _byte(self, byte: int, now: float) -> None:
        char = chr(byte)
        if char == ' ':
            self._press(_FIRE, 0, now)
        elif char in string.ascii_letters:
            upper = char.upper()
            self._letter(upper, int(Key.SHIFT) if char.isupper() else 0, now)
        elif 1 <= byte <= 26:  # Ctrl+letter
            self._letter(chr(ord('A') + byte - 1), int(Key.CTRL), now)
        else:
            self.ignored += 1

    def _letter(self, upper: str, modifiers: int, now: float) -> None:
        if upper in _LETTERS or upper in _MOUSE or upper == _PASSIVE:
            self._press(upper, modifiers, now)
        else:
            self.ignored += 1

    def _press(self, name: str, modifiers: int, now: float) -> None:
        press = self._presses.get(name)
        if press is not None and press.held(now):
            press.last, press.modifiers = now, modifiers
            return
        self._presses[name] = _Press(now, now, modifiers)
        if name == _PASSIVE:  # a new press (not a repeat) toggles
            self.passive = not self.passive

    def hands(self, now: float) -> Hands:
        """What is held at now [s]."""
        held = sorted(name for name, press in self._presses.items() if press.held(now))
        for name in [n for n in self._presses if n not in held]:
            del self._presses[name]
        keys = mouse_x = mouse_y = 0
        for name in held:
            press = self._presses[name]
            keys |= press.modifiers
            if name in _LETTERS:
                keys |= int(Key[name])
            dx, dy = _MOUSE.get(name, (0, 0))
            mouse_x += dx * MOUSE_COUNTS
            mouse_y += dy * MOUSE_COUNTS
        return Hands(keys, mouse_x, mouse_y, _FIRE in held, self.passive, tuple(held))
