"""A plugin's joint targets out (rm_msgs/ActuatorCmd) and joint states in (ActuatorState).

The vocabulary (Mode, JointTarget, JointState) is ``rm_base.joints``, shared with the
bridge and the hardware layer. A target with a NaN or infinite field is rejected before
anything is published or applied, so it never reaches a motor. No rclpy here: messages
are built and parsed as plain rm_msgs objects.
"""

from __future__ import annotations

import itertools
import threading
from collections.abc import Iterable, Mapping
from types import MappingProxyType
from typing import Any

from rm_base.joints import InvalidTargetError, JointState, JointTarget, Mode, checked
from rm_base.plugin.errors import TargetRejectedError
from rm_msgs.msg import ActuatorCmd, ActuatorState

#: {joint: target}: one coordinated set of a plugin's joint targets.
JointTargets = Mapping[str, JointTarget]
#: {joint: state}: the joint states a plugin reads (a snapshot of the view).
JointStates = Mapping[str, JointState]


def check_targets(targets: JointTargets) -> list[tuple[str, JointTarget]]:
    """Validate a plugin's joint targets where they enter, once (``rm_base.joints``).

    Raises:
        TargetRejectedError: a target is not a JointTarget, has an unknown mode, a
            NaN/infinite field or a negative MIT gain. Nothing is returned then: all
            joints or none.
    """
    out = []
    for joint, target in targets.items():
        try:
            out.append((joint, checked(target)))
        except InvalidTargetError as err:
            raise TargetRejectedError(f'target of joint {joint!r}: {err}') from None
    return out


def build_actuator_cmd(targets: JointTargets) -> ActuatorCmd:
    """Return one ActuatorCmd holding targets (header left for the caller to stamp).

    Raises:
        TargetRejectedError: as :func:`check_targets`; nothing is built then.
    """
    checked_targets = check_targets(targets)
    return ActuatorCmd(
        name=[joint for joint, _ in checked_targets],
        mode=[int(t.mode) for _, t in checked_targets],
        position=[t.position for _, t in checked_targets],
        velocity=[t.velocity for _, t in checked_targets],
        effort=[t.effort for _, t in checked_targets],
        kp=[t.kp for _, t in checked_targets],
        kd=[t.kd for _, t in checked_targets],
    )


def oldest_stamp(states: JointStates, joints: Iterable[str]) -> int:
    """The oldest state stamp [ns] of joints in states: what targets for them came from.

    0 when a joint has no state (targets not computed from states; the bridge takes them
    as a hand-written command).
    """
    oldest = 0
    for joint in joints:
        state = states.get(joint)
        if state is None:
            return 0
        if not oldest or state.stamp_ns < oldest:
            oldest = state.stamp_ns
    return oldest


_STATE_ARRAYS = (
    'position', 'velocity', 'effort', 'temperature', 'online', 'error_code', 'mode', 'command',
)


class JointStateView:
    """Latest state of every joint seen on /actuator_states.

    Each message replaces the entries of the joints it names (several bridges may publish
    disjoint sets). The callback swaps in a new read-only mapping, so readers in other
    threads never see half an update and never take a lock.

    Args:
        logger: receives one line per malformed message kind (optional).
    """

    def __init__(self, logger: Any | None = None) -> None:
        self._joints: Mapping[str, JointState] = MappingProxyType({})
        self._logger = logger
        self._write_lock = threading.Lock()
        self._reported: set[str] = set()

    def handle(self, msg: ActuatorState, receive_ns: int) -> bool:
        """Take one ActuatorState; return False (and log once) if it is malformed.

        Args:
            msg: the message; all arrays must have one entry per name (``mode`` and
                ``command`` may be empty).
            receive_ns: receive time [ns], used when the header stamp is zero.
        """
        names = msg.name
        count = len(names)
        columns = [getattr(msg, field) for field in _STATE_ARRAYS]
        lengths = dict(zip(_STATE_ARRAYS, map(len, columns), strict=True))
        optional = ('mode', 'command')
        bad = [
            field
            for field, length in lengths.items()
            if length != count and not (field in optional and length == 0)
        ]
        if bad:
            self._report(
                'lengths',
                f'ignored /actuator_states: {count} names but '
                + ', '.join(f'{lengths[f]} {f}' for f in bad),
            )
            return False
        stamp_ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        stamp_ns = stamp_ns or receive_ns
        position, velocity, effort, temperature, online, error_code, mode, command = columns
        # 200 Hz in the executor thread: one pass over the columns, positional fields.
        if not lengths['mode']:
            mode = itertools.repeat(Mode.OFF, count)
        else:
            mode = map(int, mode)
        command = map(float, command) if lengths['command'] else itertools.repeat(0.0, count)
        update = {
            joint: JointState(
                joint, float(p), float(v), float(e), float(t), bool(o), int(c), m, k, stamp_ns
            )
            for joint, p, v, e, t, o, c, m, k in zip(
                names, position, velocity, effort, temperature, online, error_code, mode,
                command, strict=True,
            )
        }
        with self._write_lock:
            merged = dict(self._joints)
            merged.update(update)
            self._joints = MappingProxyType(merged)
        return True

    def replace(self, states: Mapping[str, JointState]) -> None:
        """Take the state of every joint at once (the loop feeding the view in-process)."""
        with self._write_lock:
            self._joints = MappingProxyType(dict(states))

    def get(self, joint: str) -> JointState | None:
        """Return the state of joint, or None if never seen."""
        return self._joints.get(joint)

    def snapshot(self, joints: Iterable[str] | None = None) -> Mapping[str, JointState]:
        """Return the states of joints (all if None), read at one instant.

        Joints never seen are missing from the result.
        """
        current = self._joints
        if joints is None:
            return current
        return {j: current[j] for j in joints if j in current}

    def all_online(self, joints: Iterable[str]) -> bool:
        """Return True if every one of joints has been seen and is online."""
        current = self._joints
        return all(j in current and current[j].online for j in joints)

    def _report(self, kind: str, message: str) -> None:
        if self._logger is not None and kind not in self._reported:
            self._reported.add(kind)
            self._logger.warning(message)
