"""What the operator's client shows: the robot's state as client UI figures (pure).

One figure per name (3 bytes, the client's handle). The bars and numbers move in steps
(``BAR_STEP`` pixels, whole percent) so that a figure changes only when what it shows
does, not with every tick's noise: each change costs the link a figure.

Screen (1920 x 1080, (0, 0) bottom left): the chassis' mode, gear and power limit and the
friction wheels as text top left; the capacitor's and the barrel's bars bottom centre; a
crosshair at the aim point, green when the friction wheels are at speed.
"""

from __future__ import annotations

from dataclasses import dataclass

from rm_base.hardware.protocols.referee import (
    Color,
    Figure,
    circle,
    integer,
    line,
    rectangle,
    text_figure,
)

#: A figure and, for a text, its characters.
Item = tuple[Figure, str | None]

BAR_X, BAR_LENGTH = 760, 400
CAP_Y, HEAT_Y = 130, 180
BAR_STEP = 8  # [px] 2 % of a bar
LAYER_FRAMES, LAYER_BARS, LAYER_TEXT, LAYER_AIM = 1, 2, 3, 4


@dataclass(frozen=True)
class UiInputs:
    """What the client shows, as the plugin last heard it (None: not heard).

    Attributes:
        chassis: the chassis' mode name (``GYRO``).
        gear: its speed gear's name (``FAST``); NORMAL is not shown.
        power_limit_w: the chassis' power limit in force [W].
        shooter: the shooter's state name (``READY``).
        friction_ready: the friction wheels at speed.
        cap_energy: the capacitor's energy, 0..1.
        cap_state: what it does (``ready``, ``burst``, ``charging``, ``fault``, ``offline``).
        heat: the barrel's heat; heat_limit the referee's limit for it.
        aim: the aim point on the client's screen [px].
    """

    chassis: str | None = None
    gear: str | None = None
    power_limit_w: float | None = None
    shooter: str | None = None
    friction_ready: bool = False
    cap_energy: float | None = None
    cap_state: str | None = None
    heat: float | None = None
    heat_limit: float | None = None
    aim: tuple[int, int] = (960, 540)


def layout(inputs: UiInputs) -> dict[bytes, Item]:
    """The figures for inputs, by name."""
    items: dict[bytes, Item] = {}

    def add(figure: Figure, text: str | None = None) -> None:
        items[figure.name] = (figure, text)

    if inputs.chassis is not None:
        power = (f' {inputs.power_limit_w:.0f}W' if inputs.power_limit_w is not None
                 and inputs.power_limit_w < 10_000 else '')
        gear = f' {inputs.gear}' if inputs.gear not in (None, 'NORMAL') else ''
        words = f'{inputs.chassis}{gear}{power}'[:30]
        add(text_figure(b'CMD', (80, 820), len(words), font_size=24, layer=LAYER_TEXT,
                        color=Color.WHITE), words)
    if inputs.shooter is not None:
        words = f'FRIC {"ON" if inputs.friction_ready else "OFF"} {inputs.shooter}'[:30]
        add(text_figure(b'FRI', (80, 770), len(words), font_size=24, layer=LAYER_TEXT,
                        color=Color.GREEN if inputs.friction_ready else Color.ORANGE), words)
    if inputs.cap_state is not None:
        energy = inputs.cap_energy if inputs.cap_energy is not None else 0.0
        color = {'ready': Color.GREEN, 'burst': Color.ORANGE,
                 'charging': Color.YELLOW}.get(inputs.cap_state, Color.PINK)
        for figure in _bar(b'CP', CAP_Y, energy, color=color, width=26):
            add(figure)
        add(integer(b'CPN', (BAR_X + BAR_LENGTH + 20, CAP_Y + 12), round(100 * energy),
                    layer=LAYER_BARS, color=color))
    if inputs.heat is not None and inputs.heat_limit:
        share = inputs.heat / inputs.heat_limit
        color = Color.GREEN if share < 0.5 else Color.YELLOW if share < 0.8 else Color.PINK
        for figure in _bar(b'HT', HEAT_Y, share, color=color, width=14):
            add(figure)
    x, y = inputs.aim
    color = Color.GREEN if inputs.friction_ready else Color.ORANGE
    add(line(b'AMH', (x - 40, y), (x + 40, y), layer=LAYER_AIM, color=color))
    add(line(b'AMV', (x, y - 40), (x, y + 40), layer=LAYER_AIM, color=color))
    add(circle(b'AMC', (x, y), 20, layer=LAYER_AIM, color=color))
    return items


def _bar(prefix: bytes, y: int, share: float, *, color: Color, width: int) -> tuple[Figure, ...]:
    """An outline (``<prefix>O``) and its fill (``<prefix>B``) to share of its length."""
    steps = round(min(max(share, 0.0), 1.0) * BAR_LENGTH / BAR_STEP)
    return (
        rectangle(prefix + b'O', (BAR_X - 4, y - width // 2 - 4),
                  (BAR_X + BAR_LENGTH + 4, y + width // 2 + 4), layer=LAYER_FRAMES,
                  color=Color.WHITE),
        line(prefix + b'B', (BAR_X, y), (BAR_X + steps * BAR_STEP, y), layer=LAYER_BARS,
             color=color, width=width),
    )
