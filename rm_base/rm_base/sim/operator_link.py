"""What the simulated operator's devices share: a pty that carries what the operator holds.

A link (the DR16 receiver, the image link) sends one frame of its ``state`` at a fixed
rate while it is switched on, and is silent at start (a receiver nobody transmits to, an
image link with no client). A test (or a tool) sets the state with :meth:`hold`; a state
the frame cannot carry is refused and the old one kept.
"""

from __future__ import annotations

import abc
import dataclasses
from collections.abc import Callable, Mapping
from typing import Any, Generic, TypeVar

from rm_base.config.schema import Schema, string
from rm_base.sim.pty_port import PtyPort
from rm_base.sim_devices.errors import SimConfigError
from rm_base.sim_devices.schedule import RateSchedule

State = TypeVar('State')


class OperatorLink(abc.ABC, Generic[State]):
    """One of the operator's links on a pseudo-terminal (see the module docstring).

    Attributes:
        name: for messages.
        state: what the operator does now.
        on: the link sends (False at start).
        port: the simulated serial port the manual-control plugin opens.
    """

    def __init__(self, state: State, rate_hz: float, *, path: str, name: str) -> None:
        """Open the terminal. Raises: SimConfigError: it cannot be created."""
        self.name = name
        self.state = state
        self.on = False
        self._schedule = RateSchedule(rate_hz)
        self._frame = self._encode(state)
        self.port = PtyPort(path, name)

    @abc.abstractmethod
    def _encode(self, state: State) -> bytes:
        """The frame that carries state. Raises: ValueError: it cannot be carried."""

    def hold(self, **fields: Any) -> State:
        """Change what the operator does (fields of the state's record).

        Raises:
            SimConfigError: a value the frame cannot carry.
        """
        state = dataclasses.replace(self.state, **fields)  # type: ignore[type-var]
        try:
            self._frame = self._encode(state)
        except ValueError as err:
            raise SimConfigError(f'{self.name}: {err}') from err
        self.state = state
        return state

    def switch_on(self) -> None:
        """The link starts sending."""
        self.on = True

    def switch_off(self) -> None:
        """The link goes silent."""
        self.on = False

    def tick(self, now_ns: int) -> list[bytes]:
        """The frame due at now_ns, if any (called by the world every tick)."""
        if self._schedule.due(now_ns) and self.on:
            return [self._frame]
        return []

    def write(self, frame: bytes) -> None:
        """Write a frame to the terminal."""
        self.port.write(frame)

    def close(self) -> None:
        """Close the terminal (idempotent)."""
        self.port.close()


Link = TypeVar('Link', bound=OperatorLink[Any])


def link_schema(owner: str) -> Schema:
    """``sim.<owner>``: a terminal on a pty (the DR16 receiver, the image link)."""
    return Schema((
        string('path', nonempty=True,
           description="the pty's link, e.g. /tmp/rm_sim_${ROS_DOMAIN_ID}/"
               f'{owner} (${{VAR}} expanded)'),
        string('name', owner, description='name in logs'),
    ))


def link_from_config(kind: Callable[..., Link], config: Mapping[str, Any], owner: str) -> Link:
    """Build a link of kind from ``link_schema(owner)`` (the world's ``owner`` key).

    Raises:
        SimConfigError: a missing path or an unknown key.
    """
    values = link_schema(owner).read(owner, config, SimConfigError)
    return kind(path=values['path'], name=values['name'])
