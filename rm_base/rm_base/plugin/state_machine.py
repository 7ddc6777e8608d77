"""A small state machine over an Enum: one transition method, a table, a listener.

Every change of state goes through ``StateMachine.transition``, which checks the optional
transition table, records the reason and calls the listener (the plugin logs and publishes
``rm_msgs/PluginState`` there). No ROS here.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from enum import Enum, IntEnum
from typing import Generic, TypeVar

from rm_base.plugin.errors import TransitionError

S = TypeVar('S', bound=Enum)


class DefaultState(IntEnum):
    """States of a plugin that needs no richer machine."""

    PASSIVE = 0  # safe: no output (the joints are limp)
    ACTIVE = 1  # running normally


@dataclass(frozen=True)
class Transition(Generic[S]):
    """One change of state, handed to the listener.

    Attributes:
        previous: state before the call.
        current: state after the call (equal to previous when only the reason changed).
        reason: why, in words an operator can act on.
    """

    previous: S
    current: S
    reason: str


class StateMachine(Generic[S]):
    """Current state of an Enum-valued machine; all changes go through ``transition``.

    Thread-safe: transitions and snapshots may come from the run thread and from ROS
    callbacks; the listener runs under the machine's lock so listeners see transitions in
    order.

    Args:
        states: the Enum type of the states.
        initial: the state to start in (the safe state, usually).
        safe: a state that every state may always go to (e.g. PASSIVE); None for none.
        allowed: optional table ``{from_state: states reachable from it}``; states not in
            the table may go anywhere. Staying in a state and going to ``safe`` are always
            allowed.
        listener: called with a ``Transition`` after every accepted change.
        initial_reason: reason recorded for the initial state.
    """

    def __init__(
        self,
        states: type[S],
        initial: S,
        *,
        safe: S | None = None,
        allowed: Mapping[S, Iterable[S]] | None = None,
        listener: Callable[[Transition[S]], None] | None = None,
        initial_reason: str = 'initial state',
    ) -> None:
        for state in (initial, safe):
            if state is not None and not isinstance(state, states):
                raise TypeError(f'{state!r} is not a member of {states.__name__}')
        self._states = states
        self._safe = safe
        self._allowed = (
            {source: frozenset(targets) for source, targets in allowed.items()}
            if allowed is not None
            else None
        )
        self._listener = listener
        self._lock = threading.RLock()
        self._state = initial
        self._reason = initial_reason

    @property
    def states(self) -> type[S]:
        """The Enum type of the states."""
        return self._states

    @property
    def safe(self) -> S | None:
        """The state every state may always go to, if any."""
        return self._safe

    @property
    def state(self) -> S:
        """The current state."""
        with self._lock:
            return self._state

    @property
    def reason(self) -> str:
        """Why the last transition happened."""
        with self._lock:
            return self._reason

    def snapshot(self) -> tuple[S, str]:
        """Return (state, reason), read together."""
        with self._lock:
            return self._state, self._reason

    def can_transition(self, new_state: S) -> bool:
        """Return whether the table allows going from the current state to new_state."""
        with self._lock:
            return self._allows(self._state, new_state)

    def transition(self, new_state: S, reason: str) -> bool:
        """Go to new_state for reason; log/publish through the listener.

        Calling it again with the same state and the same reason does nothing, so a plugin
        may call it every tick. The same state with a new reason updates the reason and
        notifies the listener (the published reason must stay true).

        Args:
            new_state: member of the machine's Enum.
            reason: why, e.g. ``'no command on /chassis_cmd for 0.12 s'``.

        Returns:
            True if the state or the reason changed.

        Raises:
            TypeError: new_state is not a member of the machine's Enum.
            TransitionError: the table does not allow this transition.
        """
        if not isinstance(new_state, self._states):
            raise TypeError(f'{new_state!r} is not a member of {self._states.__name__}')
        with self._lock:
            previous = self._state
            if new_state == previous and reason == self._reason:
                return False
            if not self._allows(previous, new_state):
                raise TransitionError(
                    f'transition {previous.name} -> {new_state.name} is not allowed '
                    f'(reason given: {reason}); allowed from {previous.name}: '
                    f'{", ".join(sorted(s.name for s in self._targets(previous)))}'
                )
            self._state = new_state
            self._reason = reason
            if self._listener is not None:
                self._listener(Transition(previous, new_state, reason))
            return True

    def _allows(self, source: S, target: S) -> bool:
        if self._allowed is None or source not in self._allowed:
            return True
        return target in (source, self._safe) or target in self._allowed[source]

    def _targets(self, source: S) -> set[S]:
        targets = set(self._allowed.get(source, ())) if self._allowed else set()
        targets.add(source)
        if self._safe is not None:
            targets.add(self._safe)
        return targets
