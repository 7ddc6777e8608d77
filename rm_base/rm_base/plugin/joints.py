"""Joint targets out (rm_msgs/ActuatorCmd) and joint state in (rm_msgs/ActuatorState).

Values are at the output shaft, SI (REP 103): rad, rad/s, N·m, °C. A target with a NaN or
infinite field is rejected before anything is published, so it never reaches a motor.
No rclpy here: messages are built and parsed as plain rm_msgs objects.
"""

from __future__ import annotations

import itertools
import math
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields
from enum import IntEnum
from types import MappingProxyType
from typing import Any, NoReturn

from rm_base.plugin.errors import TargetRejectedError
from rm_msgs.msg import ActuatorCmd, ActuatorState


class ActuatorMode(IntEnum):
    """How the bridge drives a joint (rm_msgs/ActuatorCmd.MODE_*)."""

    OFF = ActuatorCmd.MODE_OFF  # no output: zero current, the joint is limp
    EFFORT = ActuatorCmd.MODE_EFFORT  # effort [N*m] as given
    VELOCITY = ActuatorCmd.MODE_VELOCITY  # velocity [rad/s], closed in the bridge
    POSITION = ActuatorCmd.MODE_POSITION  # position [rad], cascade in the bridge
    MIT = ActuatorCmd.MODE_MIT  # tau = kp*(position - q) + kd*(velocity - dq) + effort


@dataclass(frozen=True)
class JointTarget:
    """Target of one joint for one tick.

    Attributes:
        mode: how the bridge uses the fields below.
        position: [rad] (POSITION, MIT).
        velocity: [rad/s] (VELOCITY; MIT; feed-forward in POSITION).
        effort: [N*m] (EFFORT; feed-forward in MIT).
        kp: [N*m/rad], MIT only.
        kd: [N*m*s/rad], MIT only.
    """

    mode: ActuatorMode
    position: float = 0.0
    velocity: float = 0.0
    effort: float = 0.0
    kp: float = 0.0
    kd: float = 0.0

    @classmethod
    def off(cls) -> JointTarget:
        """No output: the joint goes limp."""
        return cls(ActuatorMode.OFF)

    @classmethod
    def with_effort(cls, effort: float) -> JointTarget:
        """Effort control at effort [N*m]."""
        return cls(ActuatorMode.EFFORT, effort=effort)

    @classmethod
    def with_velocity(cls, velocity: float) -> JointTarget:
        """Velocity control at velocity [rad/s]."""
        return cls(ActuatorMode.VELOCITY, velocity=velocity)

    @classmethod
    def with_position(cls, position: float, velocity: float = 0.0) -> JointTarget:
        """Position control at position [rad] with an optional velocity feed-forward [rad/s]."""
        return cls(ActuatorMode.POSITION, position=position, velocity=velocity)

    @classmethod
    def with_mit(
        cls, position: float, velocity: float, effort: float, kp: float, kd: float
    ) -> JointTarget:
        """MIT impedance control (see ``ActuatorMode.MIT``)."""
        return cls(ActuatorMode.MIT, position, velocity, effort, kp, kd)


_TARGET_FLOATS = tuple(f.name for f in fields(JointTarget) if f.name != 'mode')

# Mode value -> its int; a dict lookup accepts exactly the values ActuatorMode(value) does.
_MODE_VALUES = {int(mode): int(mode) for mode in ActuatorMode}


#: One validated joint target: (joint, mode, position, velocity, effort, kp, kd).
CheckedTarget = tuple[str, int, float, float, float, float, float]


def check_targets(targets: Mapping[str, JointTarget]) -> list[CheckedTarget]:
    """Validate joint targets where they enter, once; return them as plain tuples.

    Raises:
        TargetRejectedError: a target is not a JointTarget, has an unknown mode, a
            NaN/infinite field or a negative MIT gain. Nothing is returned then: all
            joints or none.
    """
    # Runs every tick of every plugin: plain tuples, one pass.
    isfinite = math.isfinite
    checked: list[CheckedTarget] = []
    for joint, target in targets.items():
        if not isinstance(target, JointTarget):
            raise TargetRejectedError(f'target of joint {joint!r} is not a JointTarget: {target!r}')
        try:
            mode = _MODE_VALUES[target.mode]
        except (KeyError, TypeError):
            raise TargetRejectedError(
                f'target of joint {joint!r} has unknown mode {target.mode!r}'
            ) from None
        try:
            p, v, e, k, d = (
                float(target.position), float(target.velocity), float(target.effort),
                float(target.kp), float(target.kd),
            )
        except (TypeError, ValueError):
            _reject_fields(joint, target)
        if not (isfinite(p) and isfinite(v) and isfinite(e) and isfinite(k) and isfinite(d)):
            _reject_fields(joint, target)
        if k < 0.0 or d < 0.0:
            raise TargetRejectedError(
                f'MIT gains of joint {joint!r} must be >= 0, got kp={k}, kd={d}'
            )
        checked.append((joint, mode, p, v, e, k, d))
    return checked


def build_actuator_cmd(targets: Mapping[str, JointTarget]) -> ActuatorCmd:
    """Return one ActuatorCmd holding targets (header left for the caller to stamp).

    Raises:
        TargetRejectedError: as :func:`check_targets`; nothing is built then.
    """
    checked = check_targets(targets)
    names, modes, position, velocity, effort, kp, kd = (
        (list(column) for column in zip(*checked, strict=True)) if checked
        else ([] for _ in range(7))
    )
    return ActuatorCmd(
        name=names, mode=modes, position=position, velocity=velocity, effort=effort,
        kp=kp, kd=kd,
    )


def _reject_fields(joint: str, target: JointTarget) -> NoReturn:
    """Raise TargetRejectedError naming the first field of target that is not finite."""
    for field in _TARGET_FLOATS:
        value = getattr(target, field)
        try:
            number = float(value)
        except (TypeError, ValueError):
            number = math.nan
        if not math.isfinite(number):
            raise TargetRejectedError(
                f'{field} of joint {joint!r} is not a finite number: {value!r}'
            )
    raise AssertionError(f'target of joint {joint!r} has no field to reject: {target!r}')


@dataclass(frozen=True)
class JointState:
    """Last reported state of one joint (from rm_msgs/ActuatorState).

    Attributes:
        position: [rad], continuous (multi-turn).
        velocity: [rad/s].
        effort: [N*m].
        temperature: [degC]; NaN where the device reports none.
        online: feedback seen within the bridge's offline timeout.
        error_code: device error code, 0 = none.
        mode: ActuatorMode the bridge actually applies (OFF when held safe).
        command: output actually sent [N*m] after every clamp.
        stamp_ns: header stamp of the message (receive time if zero) [ns].
    """

    position: float
    velocity: float
    effort: float
    temperature: float
    online: bool
    error_code: int
    mode: int
    command: float
    stamp_ns: int


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
            mode = itertools.repeat(ActuatorMode.OFF, count)
        else:
            mode = map(int, mode)
        command = map(float, command) if lengths['command'] else itertools.repeat(0.0, count)
        update = {
            joint: JointState(
                float(p), float(v), float(e), float(t), bool(o), int(c), m, k, stamp_ns
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
