"""Keep the operator's client showing a set of figures, one 0x0301 frame at a time (pure).

The client keeps every figure it was given until told otherwise, so only changes go out:
a figure not shown is added, a changed one modified, one no longer wanted deleted. A
frame carries up to 7 figure changes (graphics), or one text (the 0x0110 frame holds
nothing else); graphics and texts take turns when both wait. Nothing tells the robot that
the client restarted (it then shows nothing), so the figures are re-added, a frame at a
time, every ``refresh_s`` while nothing else waits; :meth:`UiSync.resend` starts over at
once (clear the client, add everything), for the moments a client is known to (re)connect.
"""

from __future__ import annotations

import collections
from collections.abc import Mapping
from dataclasses import replace

from rm_base.hardware.protocols.referee import (
    DeleteOp,
    Figure,
    FigureOp,
    deletion,
    drawing,
    text_drawing,
)

from rm_plugins.ui.layout import Item

_NS_PER_S = 1_000_000_000
MAX_FIGURES = 7


class UiSync:
    """What the client shows, as far as the robot knows, and the next frame to send.

    Args:
        refresh_s: re-add the shown figures this often [s].
    """

    def __init__(self, refresh_s: float) -> None:
        self.shown: dict[bytes, Item] = {}
        self._refresh_ns = round(refresh_s * _NS_PER_S)
        self._clear = True  # a client may show another run's figures: clear it first
        self._text_turn = False
        self._refresh: collections.deque[bytes] = collections.deque()
        self._next_refresh_ns: int | None = None

    def resend(self) -> None:
        """Clear the client and draw everything again, from the next frame on."""
        self.shown.clear()
        self._refresh.clear()
        self._clear = True

    def next_frame(self, wanted: Mapping[bytes, Item], now_ns: int) -> tuple[int, bytes] | None:
        """(content id, content) of the next frame, or None when the client is up to date."""
        if self._clear:
            self._clear = False
            return deletion(DeleteOp.ALL)
        shown = self.shown
        gone = [name for name in shown if name not in wanted]
        new = [name for name, item in wanted.items() if shown.get(name) != item]
        texts = [name for name in new if wanted[name][1] is not None]
        graphics = [name for name in new if wanted[name][1] is None]
        if (gone or graphics) and not (texts and self._text_turn):
            self._text_turn = True
            return self._graphics(gone, graphics, wanted)
        if texts:
            self._text_turn = False
            return self._text(texts[0], wanted[texts[0]], FigureOp.MODIFY
                              if texts[0] in shown else FigureOp.ADD)
        return self._refresh_frame(now_ns)

    def _graphics(self, gone: list[bytes], changed: list[bytes],
                  wanted: Mapping[bytes, Item]) -> tuple[int, bytes]:
        figures: list[Figure] = []
        for name in gone[:MAX_FIGURES]:
            figure = self.shown.pop(name)[0]
            figures.append(replace(figure, op=FigureOp.DELETE))
        for name in changed[:MAX_FIGURES - len(figures)]:
            figure = wanted[name][0]
            op = FigureOp.MODIFY if name in self.shown else FigureOp.ADD
            figures.append(replace(figure, op=op))
            self.shown[name] = wanted[name]
        return drawing(figures)

    def _text(self, name: bytes, item: Item, op: FigureOp) -> tuple[int, bytes]:
        figure, text = item
        self.shown[name] = item
        return text_drawing(replace(figure, op=op), text or '')

    def _refresh_frame(self, now_ns: int) -> tuple[int, bytes] | None:
        """Re-add shown figures (a client that restarted has none), in turn."""
        if not self._refresh:
            if self._next_refresh_ns is None:
                self._next_refresh_ns = now_ns + self._refresh_ns
            if now_ns < self._next_refresh_ns or not self.shown:
                return None
            self._refresh.extend(self.shown)
            self._next_refresh_ns = now_ns + self._refresh_ns
        queue, shown = self._refresh, self.shown
        while queue and queue[0] not in shown:
            queue.popleft()
        if not queue:
            return None
        first = shown[queue[0]]
        if first[1] is not None:
            queue.popleft()
            return text_drawing(replace(first[0], op=FigureOp.ADD), first[1])
        figures: list[Figure] = []
        while queue and len(figures) < MAX_FIGURES:
            item = shown.get(queue[0])
            if item is not None and item[1] is not None:
                break  # a text goes in a frame of its own, next
            queue.popleft()
            if item is not None:
                figures.append(replace(item[0], op=FigureOp.ADD))
        return drawing(figures)
