"""Command inputs: the latest message on a command topic, with a stamp and a timeout.

A command is valid for ``timeout`` seconds from its stamp (``header.stamp``), or from the
time it was received when it has no header or a zero stamp. A message whose stamp is
already older than the timeout when it arrives is rejected as stale (and logged). Once the
newest command is older than the timeout the input reads "no command", and the reason is
logged once; its return is logged once too.

The subscription callback (ROS executor thread) and the plugin's run thread share one
latest-value slot guarded by a lock, so a reader always gets a message and its stamp from
the same callback. No rclpy here: the caller passes times in nanoseconds.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from enum import Enum, IntEnum
from typing import Any, Generic, Protocol, TypeVar

from rm_base.errors import InputRejectedError

M = TypeVar('M')
C = TypeVar('C', bound=IntEnum)

_NS_PER_S = 1_000_000_000


class Logger(Protocol):
    """The part of rclpy's logger a command input uses."""

    def info(self, message: str) -> Any:
        """Log at INFO."""

    def warning(self, message: str) -> Any:
        """Log at WARN."""


class CommandStatus(Enum):
    """Whether an input holds a command that may be used now."""

    FRESH = 'fresh'  # a command within its timeout
    NEVER_RECEIVED = 'never received'  # nothing since start or since the last clear()
    TIMED_OUT = 'timed out'  # the newest command is older than the timeout


def stamp_ns_of(msg: object) -> int | None:
    """Return msg.header.stamp in nanoseconds, or None without a header or with a zero stamp."""
    header = getattr(msg, 'header', None)
    stamp = getattr(header, 'stamp', None)
    if stamp is None:
        return None
    stamp_ns = int(stamp.sec) * _NS_PER_S + int(stamp.nanosec)
    return stamp_ns or None


class LatestMessage:
    """The newest message of a topic and its time, from a subscription callback to run().

    For inputs that are not commands (no watchdog, no stale check): the IMU, odometry.
    ``put`` is the subscription callback; ``get`` returns ``(msg, time_ns)`` or None.

    Args:
        use_stamp: the message's time is its header stamp (the receive time when it has
            none); False: always the receive time.
    """

    def __init__(self, *, use_stamp: bool = True) -> None:
        self._use_stamp = use_stamp
        self._lock = threading.Lock()
        self._value: tuple[Any, int] | None = None

    def put(self, msg: Any, receive_ns: int) -> None:
        """Keep msg as the newest (any thread)."""
        time_ns = (stamp_ns_of(msg) or receive_ns) if self._use_stamp else receive_ns
        with self._lock:
            self._value = (msg, time_ns)

    def get(self) -> tuple[Any, int] | None:
        """The newest message and its time [ns], or None before the first."""
        with self._lock:
            return self._value


class LogThrottle:
    """One log line per period for a kind of event; counts the ones held back.

    Args:
        period_ns: shortest time between two lines [ns].
    """

    def __init__(self, period_ns: int) -> None:
        self._period_ns = period_ns
        self._next_ns: int | None = None
        self._held = 0

    def due(self, now_ns: int) -> str | None:
        """Whether to log an event at now_ns, and how to end its line.

        Returns:
            None: hold this one back. Else log now and end the line with the text
            returned: `` (N more since the last report)``, or empty.
        """
        if self._next_ns is not None and now_ns < self._next_ns:
            self._held += 1
            return None
        self._next_ns = now_ns + self._period_ns
        held, self._held = self._held, 0
        return f' ({held} more since the last report)' if held else ''


def message_constant(kind: type[C], value: int, field: str) -> C:
    """The member of kind that a message's constant field holds, or a rejection naming all.

    Raises:
        InputRejectedError: ``unknown <field> <value> (known: 0=PASSIVE, 1=...)``.
    """
    try:
        return kind(int(value))
    except ValueError:
        known = ', '.join(f'{m.value}={m.name}' for m in kind)
        raise InputRejectedError(f'unknown {field} {value} (known: {known})') from None


class CommandInput(Generic[M]):
    """The latest valid command on one topic, valid for a timeout from its stamp.

    The one place a command is checked: a message is parsed once, as it is taken
    (``parse``: finite, in range, a known mode, into a frozen record); a message that fails,
    or is stale, is rejected, counted and logged (throttled), and never replaces the last
    valid command, which stands until its own timeout. ``latest`` hands the plugin the
    record, never the message.

    Args:
        topic: topic name, for messages.
        timeout: how long a command stays valid after its stamp [s]; > 0.
        logger: receives the rejected / no-command / resumed lines.
        watchdog: whether the plugin falls back to its safe state while this input has
            no command (see ``PluginBase.subscribe_command``).
        log_period: shortest interval between two "rejected" lines [s].
        parse: the message -> its checked record; raises InputRejectedError with the
            reason. None: the message is the record.
    """

    def __init__(
        self,
        topic: str,
        timeout: float,
        logger: Logger,
        *,
        watchdog: bool = True,
        log_period: float = 1.0,
        parse: Callable[[Any], M] | None = None,
    ) -> None:
        if not timeout > 0.0:
            raise ValueError(f'timeout of {topic} must be > 0 s, got {timeout}')
        self.topic = topic
        self.timeout = float(timeout)
        self.watchdog = watchdog
        self._timeout_ns = round(timeout * _NS_PER_S)
        self._logger = logger
        self._lock = threading.Lock()
        self._msg: M | None = None
        self._stamp_ns = 0
        self._rejected = 0
        self._parse = parse
        self._rejection = ''  # why the newest message was refused, if it was
        self._logged_rejection = ''  # the last rejection that got its own log line
        self._last_rejection = ''  # the newest rejection's reason, kept past valid messages
        self._stale_log = LogThrottle(round(log_period * _NS_PER_S))
        # Run-thread side: whether the current "no command" episode has been reported, and
        # its kind and reason.
        self._reported_missing = False
        self._episode: tuple[tuple[CommandStatus, bool], str] | None = None

    @property
    def rejected(self) -> int:
        """Number of messages rejected (stale, from the future, or invalid) since start."""
        with self._lock:
            return self._rejected

    def rejections(self) -> tuple[int, str]:
        """The messages rejected since start and why the newest was ('' if none was)."""
        with self._lock:
            return self._rejected, self._last_rejection

    def handle(self, msg: Any, receive_ns: int) -> bool:
        """Take a message from the subscription: check it once and keep its record.

        Args:
            msg: the message; its ``header.stamp`` is used when present and non-zero.
            receive_ns: receive time on the node's clock [ns].

        Returns:
            True if stored, False if rejected (stale, stamped in the future, or invalid).
        """
        stamp_ns = stamp_ns_of(msg)
        if stamp_ns is None:
            stamp_ns = receive_ns
        age_ns = receive_ns - stamp_ns
        # A stamp more than a timeout in the future means the sender's clock is off; using
        # it would keep the command alive past its timeout.
        if age_ns > self._timeout_ns or -age_ns > self._timeout_ns:
            when = (
                f'{age_ns / _NS_PER_S:.3f} s old'
                if age_ns > 0
                else f'{-age_ns / _NS_PER_S:.3f} s in the future (clocks out of sync?)'
            )
            stale = f'stamp is {when}, timeout {self.timeout:.3f} s'
            with self._lock:
                self._rejected += 1
                self._last_rejection = f'stale: {stale}'
                more = self._stale_log.due(receive_ns)
            if more is not None:
                self._logger.warning(f'rejected stale command on {self.topic}: {stale}{more}')
            return False
        record: M = msg
        if self._parse is not None:
            try:
                record = self._parse(msg)
            except InputRejectedError as err:
                self._reject(f'rejected {self.topic}: {err}', receive_ns)
                return False
        with self._lock:
            self._rejection = ''
            self._msg = record
            # a stamp ahead of this clock (within the timeout: clocks a little apart) counts
            # from its receipt, so no command outlives its timeout after its last message
            self._stamp_ns = min(stamp_ns, receive_ns)
        return True

    def _reject(self, reason: str, receive_ns: int) -> None:
        with self._lock:
            self._rejected += 1
            self._rejection = self._last_rejection = reason
            more = self._stale_log.due(receive_ns)
            stands = self._msg is not None
            if more is not None:
                self._logged_rejection = reason
        if more is not None:
            outcome = (
                'the last valid command stands until its timeout' if stands
                else 'no valid command has come yet'
            )
            self._logger.warning(f'{reason}; {outcome}{more}')

    def status(self, now_ns: int) -> tuple[CommandStatus, str]:
        """Return the status at now_ns and, unless FRESH, why there is no command."""
        with self._lock:
            msg, stamp_ns = self._msg, self._stamp_ns
        return self._evaluate(msg, stamp_ns, now_ns)

    def check(self, now_ns: int) -> str | None:
        """Return None while a command is fresh, else the reason; log each change once.

        Call from the run thread only (``latest`` does the same and returns the command).
        """
        with self._lock:
            msg, stamp_ns = self._msg, self._stamp_ns
        return self._report(*self._evaluate(msg, stamp_ns, now_ns))

    def latest(self, now_ns: int) -> M | None:
        """Return the newest command if still within its timeout at now_ns, else None.

        Call from the run thread only; a change between "command" and "no command" is
        logged once, as in ``check``.
        """
        with self._lock:
            msg, stamp_ns = self._msg, self._stamp_ns
        if self._report(*self._evaluate(msg, stamp_ns, now_ns)) is not None:
            return None
        return msg

    def _evaluate(self, msg: M | None, stamp_ns: int, now_ns: int) -> tuple[CommandStatus, str]:
        rejection = self._rejection
        if msg is None:
            return CommandStatus.NEVER_RECEIVED, rejection or f'no command on {self.topic} yet'
        age_ns = now_ns - stamp_ns
        if age_ns > self._timeout_ns:
            since = f' since: {rejection}' if rejection else ''
            return (
                CommandStatus.TIMED_OUT,
                f'no {"valid " if rejection else ""}command on {self.topic} for '
                f'{age_ns / _NS_PER_S:.3f} s (timeout {self.timeout:.3f} s){since}',
            )
        return CommandStatus.FRESH, ''

    def _report(self, status: CommandStatus, reason: str) -> str | None:
        """Log each start of a "no command" episode once; return its reason (stable text).

        A rejection while there is no command starts a new episode (the reason then says
        why the messages coming in are not commands); more rejections do not.
        """
        if status is CommandStatus.FRESH:
            if self._reported_missing:
                self._reported_missing = False
                self._episode = None
                self._logger.info(f'command on {self.topic} resumed')
            return None
        key = (status, bool(self._rejection))
        if self._episode is None or self._episode[0] != key:
            self._reported_missing = True
            self._episode = (key, reason)
            with self._lock:
                # a rejection's own line already said it: one bad message, one warning
                said = status is CommandStatus.NEVER_RECEIVED and reason == self._logged_rejection
            if not said:
                self._logger.warning(reason)
        return self._episode[1]

    def stamp_ns(self) -> int | None:
        """Return the stamp of the stored command [ns] (receive time if it had none)."""
        with self._lock:
            return self._stamp_ns if self._msg is not None else None

    def clear(self) -> None:
        """Forget the stored command (on enable/disable: never act on an old command)."""
        with self._lock:
            self._msg = None
            self._stamp_ns = 0
            self._rejection = ''
            self._logged_rejection = ''
        self._reported_missing = False
        self._episode = None
