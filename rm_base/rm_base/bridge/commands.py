"""Validation of rm_msgs/ActuatorCmd: a message is applied whole, or not at all.

Several plugins publish /actuator_cmd, each message carrying a subset of the joints. A
message is *well-formed* when its seven arrays have one entry per name, no name repeats,
every name is a joint of this bridge, every mode is an ``ActuatorCmd.MODE_*``, every value
is finite (unused fields too) and the MIT gains are >= 0.

A message is also *fresh* when its ``header.stamp`` is zero (a sender that does not stamp)
or within ``safety.command_timeout_s`` of the bridge's clock (:func:`check_stamp`): a
command delayed or replayed from long ago (or from a sender whose clock is far ahead) would
otherwise be applied as new, and drive a motor for another command timeout.

A message is also computed from *this bridge's* states (:func:`check_states_stamp`): its
``states_stamp`` is zero (not computed from states) or no older than the first states this
bridge published. After a restart the bridge's encoders count from a new zero, so a
position computed against the old bridge's states would drive the motor somewhere else
(docs/RELIABILITY.md, "A restarted bridge").

Only a well-formed, fresh message is applied, all of its joints in the same callback; one bad
entry rejects the whole message. A plugin's message is one coordinated set of targets
(four mecanum wheels, a yaw/pitch pair): applying three of four wheels would turn a
straight drive into a spin, while holding the previous complete set is safe because the
hardware layer zeroes any joint whose command is older than ``safety.command_timeout_s``.
Messages of different plugins never share joints, so one plugin's bad message leaves the
other plugins' joints alone.

No rclpy here: the message is read through its attributes.
"""

from __future__ import annotations

from collections.abc import Container, Sequence
from typing import Protocol

from rm_base.bridge.errors import ActuatorCmdRejectedError, Rejection
from rm_base.joints import InvalidTargetError, JointTarget, check_target

_FIELDS = ('mode', 'position', 'velocity', 'effort', 'kp', 'kd')


class ActuatorCmdLike(Protocol):
    """The fields of rm_msgs/ActuatorCmd that are read."""

    name: Sequence[str]
    mode: Sequence[int]
    position: Sequence[float]
    velocity: Sequence[float]
    effort: Sequence[float]
    kp: Sequence[float]
    kd: Sequence[float]


def check_stamp(msg: object, now_ns: int, timeout_s: float) -> int:
    """Reject a message stamped more than ``timeout_s`` before (or after) ``now_ns``.

    Args:
        msg: the message; a missing header or a zero stamp passes.
        now_ns: the bridge's clock [ns] (the ROS clock the senders stamp with).
        timeout_s: safety.command_timeout_s [s].

    Returns:
        The message's age [ns]: how long ago it was stamped (0 without a stamp, or for a
        stamp slightly ahead of ``now_ns``). The command timeout runs from its stamp, not
        from its arrival: time spent in queues (a busy sender or receiver) counts.

    Raises:
        ActuatorCmdRejectedError: ``Rejection.STALE``.
    """
    stamp = getattr(getattr(msg, 'header', None), 'stamp', None)
    if stamp is None or not (stamp.sec or stamp.nanosec):
        return 0
    age_ns = now_ns - (stamp.sec * 1_000_000_000 + stamp.nanosec)
    age_s = age_ns / 1e9
    if abs(age_s) > timeout_s:
        when = f'{age_s:.3f} s old' if age_s > 0 else f'{-age_s:.3f} s in the future'
        raise ActuatorCmdRejectedError(
            Rejection.STALE, f'stamp is {when} (command timeout {timeout_s:g} s)'
        )
    return max(0, int(age_ns))


def first_states_stamp(first_ns: int | None, stamp_ns: int) -> int:
    """The stamp this bridge's states count from, after publishing states stamped stamp_ns.

    The first stamp it published; a clock that went back (simulated time replayed again)
    starts the count anew, else every target computed since would be refused.
    """
    return stamp_ns if first_ns is None or stamp_ns < first_ns else first_ns


def check_states_stamp(msg: object, first_states_ns: int | None) -> None:
    """Reject a message computed from states this bridge did not publish.

    Args:
        msg: the message; a missing ``states_stamp`` or a zero one passes.
        first_states_ns: stamp [ns] of the first states this bridge published (None
            before it published any). The sender echoes stamps of this bridge's clock,
            so the two compare whatever the sender's clock.

    Raises:
        ActuatorCmdRejectedError: ``Rejection.OLD_STATES``.
    """
    stamp = getattr(msg, 'states_stamp', None)
    if stamp is None or not (stamp.sec or stamp.nanosec):
        return
    if first_states_ns is None:
        raise ActuatorCmdRejectedError(
            Rejection.OLD_STATES, 'computed from joint states, and this bridge has sent none yet'
        )
    before_s = (first_states_ns - (stamp.sec * 1_000_000_000 + stamp.nanosec)) / 1e9
    if before_s > 0:
        raise ActuatorCmdRejectedError(
            Rejection.OLD_STATES,
            f"computed from joint states {before_s:.3f} s older than this bridge's first "
            '(another bridge, before a restart)',
        )


def parse_actuator_cmd(
    msg: ActuatorCmdLike, joints: Container[str]
) -> list[tuple[str, JointTarget]]:
    """Validate a whole ActuatorCmd and return its targets.

    Args:
        msg: the message.
        joints: names of the joints this bridge drives.

    Returns:
        (joint, target) per entry, in message order (empty for an empty message).

    Raises:
        ActuatorCmdRejectedError: the message is not well-formed (see the module
            docstring); ``reason`` says which rule it broke.
    """
    names = list(msg.name)
    count = len(names)
    columns = {field: list(getattr(msg, field)) for field in _FIELDS}
    lengths = {field: len(values) for field, values in columns.items()}
    if any(n != count for n in lengths.values()):
        bad = ', '.join(f'{n} {f}' for f, n in lengths.items() if n != count)
        raise ActuatorCmdRejectedError(
            Rejection.LENGTH_MISMATCH, f'{count} names but {bad} (all arrays need one per name)'
        )
    if len(set(names)) != count:
        twice = sorted({n for n in names if names.count(n) > 1})
        raise ActuatorCmdRejectedError(Rejection.DUPLICATE_JOINT, f'joint(s) named twice: {twice}')
    unknown = [n for n in names if n not in joints]
    if unknown:
        raise ActuatorCmdRejectedError(
            Rejection.UNKNOWN_JOINT, f'unknown joint(s) {unknown} (not driven by this bridge)'
        )
    targets = []
    mode, position, velocity, effort, kp, kd = (columns[field] for field in _FIELDS)
    for i, name in enumerate(names):
        try:
            target = check_target(
                mode[i], position=position[i], velocity=velocity[i], effort=effort[i],
                kp=kp[i], kd=kd[i],
            )
        except InvalidTargetError as err:
            raise ActuatorCmdRejectedError(Rejection(err.problem.value), f'{name}: {err}') from None
        targets.append((name, target))
    return targets
