"""The unsafe-frame checker: reads every CAN frame on the wire and flags unsafe commands.

Why one module: the checker decodes every family's frames against one model of what is safe;
split by family, each part would need the whole model.

:class:`WireChecker` is fed the frames of every bus in wire order (from an rm_sim tap, a
python-can log, a socketcan sniffer) and, optionally, the /actuator_cmd messages the
bridge was sent. It decodes every command frame the robot config implies, independently
of the bridge's actuator code:

* DJI group frames (0x200, 0x1FF, 0x2FF, 0x1FE, 0x2FE): each slot's raw value, turned
  into the joint effort it asks for (current kinds: raw x A/raw x N·m/A; GM6020 voltage:
  ``(V - Ke·ω) / R · Kt`` with ω from the motor's own feedback on the wire);
* MIT frames (Damiao, Cheetah): the torque the motor will apply,
  ``kp·(p − q) + kd·(v − dq) + τ`` with q, dq from its latest feedback on the wire.

A command frame is unsafe (a :class:`Violation`) when

* ``effort``: it asks a joint for more than the joint's configured ``max_effort`` (plus
  one quantisation step and ``effort_tolerance``), or a DJI raw beyond the kind's limit;
* ``unknown_slot``: a DJI slot with no configured joint is not zero;
* ``offline``: it is not zero although the joint sent no feedback for longer than
  ``safety.feedback_timeout_s`` (never any feedback counts too);
* ``over_temperature`` / ``device_fault``: it is not zero although the joint's feedback
  said it is too hot or in a fault state, and has not since said otherwise for
  ``safety.fault_clear_s`` (below the hysteresis, or no fault);
* ``injected_<kind>``: it is not zero although the checker's own record of the faults
  injected into the motor (:meth:`WireChecker.note_fault`, told by the harness that injects
  them, never read off the wire) says the motor is offline or too hot, or was within
  ``safety.fault_clear_s`` (plus the feedback timeout for a motor that went silent). Garbage
  frames cannot talk the checker out of this rule, whatever they say;
* ``no_command``: it is not zero although the joint has had no fresh, valid command
  (ActuatorCmd with finite values, a known mode other than MODE_OFF, a stamp within the
  command timeout) for longer than ``safety.command_timeout_s`` — only when commands are
  fed (:meth:`WireChecker.note_command`), from the first one noted for the joint on (a
  checker joining a running robot cannot know the commands before it);
* ``malformed``: a command frame that does not decode (wrong length).

The timing rules allow ``grace_s`` after the moment the joint had to be zero (the bridge
acts on its next tick, and under CPU load its receive thread stamps feedback late); the
latency of every "had to go to zero" episode is measured, so a test can assert it tightly.
A frame sent after a stall of the bridge's process (a gap in its command frames) is judged
at the time it was decided, not sent; stalls are counted.
NaN cannot be encoded in a DJI or MIT frame; :func:`check_actuator_states` checks the
reported commands on /actuator_states for NaN and the same limits.

Frames must carry wire time in ``msg.timestamp`` [s] (rm_sim stamps them; so does
python-can on a real bus). Memory is bounded: only the first ``keep`` violations are
kept, the rest are counted.
"""

from __future__ import annotations

import collections
import dataclasses
import math
from collections.abc import Iterable, Mapping
from typing import Any

import can
from rm_base.hardware import HardwareConfig, Mode
from rm_base.hardware.actuators import Actuator, MitActuator
from rm_base.hardware.errors import ProtocolError
from rm_base.hardware.protocols import mit
from rm_base.motors import actuator_class
from rm_base.motors.cheetah import protocol as cheetah
from rm_base.motors.cheetah.actuator import Cheetah
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.dji import protocol as dji
from rm_base.motors.dji.actuator import DjiActuator, Gm6020Voltage

_NS_PER_S = 1_000_000_000
_NEVER = -math.inf
#: Frames within this of the first frame after a stall belong to the same tick [s].
_BURST_S = 0.0005


@dataclasses.dataclass(frozen=True)
class Violation:
    """One unsafe command frame.

    Attributes:
        time: wire time of the frame [s].
        bus: bus name.
        can_id: arbitration id of the frame.
        joint: the joint the offending value is for ('' for an unknown slot).
        rule: ``effort``, ``unknown_slot``, ``offline``, ``over_temperature``,
            ``device_fault``, ``no_command`` or ``malformed``.
        detail: what was on the wire and what was allowed.
        after_stall: ``(ms since, stall ms)`` if the frame came within ``stall_window_s``
            after a stall of the bridge's process (see WireChecker), else None.
    """

    time: float
    bus: str
    can_id: int
    joint: str
    rule: str
    detail: str
    after_stall: tuple[float, float] | None = None

    def __str__(self) -> str:
        text = (
            f'{self.time:.4f} {self.bus} 0x{self.can_id:03X} {self.joint or "-"}: '
            f'{self.rule}: {self.detail}'
        )
        if self.after_stall is not None:
            text += f' [{self.after_stall[0]:.0f} ms after a {self.after_stall[1]:.0f} ms stall]'
        return text


@dataclasses.dataclass
class JointStats:
    """What the checker saw of one joint.

    Attributes:
        command_frames: command frames (or slots) decoded for it.
        nonzero_frames: of those, the ones asking for output.
        max_effort_seen: largest |effort| asked on the wire [N·m].
        zero_latencies: per episode in which the joint had to be zeroed (offline,
            over-temperature, fault, no command), seconds from the moment it had to be
            zero to the first zero frame.
        feedback_frames: feedback frames decoded (garbage that does not decode excluded).
    """

    command_frames: int = 0
    nonzero_frames: int = 0
    max_effort_seen: float = 0.0
    zero_latencies: list[float] = dataclasses.field(default_factory=list)
    feedback_frames: int = 0


class _Window:
    """Sliding min and max of a value over the last ``span_s`` seconds (never fewer than the
    last two samples), in O(1) amortised per sample.

    The last ``span_s + HISTORY_S`` seconds of samples are also kept, for frames decided
    before a stall and sent after it (``bounds(since=...)``): the bridge decided them with
    feedback from before the stall, which the sliding window may have let go meanwhile.

    Times and values sit in parallel deques of floats, not (t, x) tuples: a soak feeds it
    tens of thousands of samples a second, and new tuples that replace older ones fill the
    garbage collector's youngest generation without ever making a collection due, so the
    loop sharing the process scans them all at once (docs/PERFORMANCE.md, "The soak").
    """

    HISTORY_S = 2.0  # [s] longer than any stall a test lets pass

    def __init__(self, span_s: float) -> None:
        self.span_s = span_s
        deque = collections.deque
        self._history: tuple[collections.deque[float], collections.deque[float]] = (
            deque(), deque()
        )
        self._samples: tuple[collections.deque[float], collections.deque[float]] = (
            deque(), deque()
        )
        # monotonic deques: increasing values (the minimum first), decreasing values
        self._lo: tuple[collections.deque[float], collections.deque[float]] = (deque(), deque())
        self._hi: tuple[collections.deque[float], collections.deque[float]] = (deque(), deque())

    def add(self, t: float, x: float) -> None:
        history_t, history_x = self._history
        history_t.append(t)
        history_x.append(x)
        while history_t[0] < t - self.span_s - self.HISTORY_S:
            history_t.popleft()
            history_x.popleft()
        samples_t, samples_x = self._samples
        samples_t.append(t)
        samples_x.append(x)
        lo_t, lo_x = self._lo
        while lo_x and lo_x[-1] >= x:
            lo_t.pop()
            lo_x.pop()
        lo_t.append(t)
        lo_x.append(x)
        hi_t, hi_x = self._hi
        while hi_x and hi_x[-1] <= x:
            hi_t.pop()
            hi_x.pop()
        hi_t.append(t)
        hi_x.append(x)
        while len(samples_t) > 2 and samples_t[0] < t - self.span_s:
            old_t = samples_t.popleft()
            samples_x.popleft()
            for mono_t, mono_x in (self._lo, self._hi):
                while mono_t and mono_t[0] <= old_t:
                    mono_t.popleft()
                    mono_x.popleft()

    def bounds(self, since: float | None = None) -> tuple[float, float] | None:
        """(min, max) over the window, or None before any sample.

        Args:
            since: also over every kept sample from this time on [s] (an O(n) scan, for
                the few frames sent after a stall).
        """
        if not self._samples[0]:
            return None
        lo, hi = self._lo[1][0], self._hi[1][0]
        if since is not None:
            older = [x for tx, x in zip(*self._history, strict=True) if tx >= since]
            lo, hi = min([lo, *older]), max([hi, *older])
        return lo, hi

    @property
    def last(self) -> float:
        return self._samples[1][-1]


def _min_abs(lo: float, hi: float) -> float:
    """The value of smallest magnitude in [lo, hi] (signed)."""
    if lo <= 0.0 <= hi:
        return 0.0
    return lo if abs(lo) < abs(hi) else hi


class _Joint:
    """The checker's view of one joint: limits from the config, feedback from the wire."""

    def __init__(self, actuator: Actuator, hysteresis_c: float, window_s: float) -> None:
        self.name = actuator.name
        self.shadow = actuator  # only its decoder and resolved limits are used
        self.max_effort = actuator.max_effort
        self.temperature_limit = actuator.temperature_limit
        self.temperature_resume = actuator.temperature_limit - hysteresis_c
        self.last_feedback_t = _NEVER  # newest decoded feedback [s]
        # what the motor reported over the feedback the bridge may still be acting on:
        # rotor/motor velocity [rad/s] and (MIT) the motor-side position [rad]
        self.velocity = _Window(window_s)
        self.position = _Window(window_s)
        self.overheated_since: float | None = None
        self.cool_since: float | None = None  # below the hysteresis since
        self.fault_since: float | None = None
        self.fault_gone_since: float | None = None
        # the harness's record of injected faults: kind -> (since, cleared at or None)
        self.injected: dict[str, tuple[float, float | None]] = {}
        self.command_until = _NEVER  # fresh command valid until [s]
        self.commanded = False  # a command was noted (the rule starts there)
        # the current "must be zero" episode: since when, and whether zero was reached
        self.episode_since: float | None = None
        self.episode_zeroed = False
        self.stats = JointStats()
        self.timeline: list[tuple[float, float, bool]] = []

    def last_feedback(self) -> float:
        return self.last_feedback_t


class WireChecker:
    """Flags unsafe command frames; see the module docstring.

    Args:
        config: the bridge's hardware config (dict schema of rm_base.hardware.config, or
            a parsed HardwareConfig): joints, limits and safety timeouts.
        grace_s: time allowed after a joint had to be zero before a non-zero frame is a
            violation [s].
        effort_tolerance: extra effort allowed over max_effort [N·m], on top of one
            quantisation step of the frame's encoding.
        track_commands: apply the ``no_command`` rule (feed commands with note_command).
        keep: violations kept (the rest are only counted).
        record: keep every joint's ``(time, effort, non-zero)`` per command frame in
            ``timeline(joint)`` (tests; unbounded, so not in a soak).
        stall_s: a gap this long in the bridge's command frames on a bus is a stall of
            its process (see ``_decision_time``) [s]; None: frames are judged at the time
            they were sent (lockstep, hand-made traffic).
        stall_window_s: a violation this soon after a stall is marked ``after_stall``
            (counted apart in the summary; still a violation) [s].
        feedback_window_s: the effort of a GM6020 voltage or an MIT frame depends on
            the motor's speed (and position); it is judged with the most favourable value
            the motor reported within this window (at least the last two frames), since
            the bridge may act on any feedback it has not yet timed out. 0 in lockstep;
            the feedback timeout in real time.
    """

    def __init__(
        self,
        config: Mapping[str, Any] | HardwareConfig,
        *,
        grace_s: float = 0.002,
        effort_tolerance: float = 0.0,
        track_commands: bool = False,
        keep: int = 100,
        record: bool = False,
        stall_s: float | None = None,
        stall_window_s: float = 0.5,
        feedback_window_s: float = 0.0,
    ) -> None:
        if not isinstance(config, HardwareConfig):
            config = HardwareConfig.from_dict(config)
        self.config = config
        self.grace_s = grace_s
        self.effort_tolerance = effort_tolerance
        self.track_commands = track_commands
        self._keep = keep
        self._record = record
        self.stall_s = stall_s
        self._tick_s = 1.0 / config.rate_hz
        self._last_tx: dict[str, float] = {}
        self._burst: dict[str, tuple[float, float]] = {}
        self._last_stall: dict[str, tuple[float, float]] = {}  # bus -> (end, length ms)
        self.stall_window_s = stall_window_s
        self.feedback_window_s = feedback_window_s
        self.violations_by_rule: dict[str, int] = {}
        self.violations_after_stall = 0
        self.stalls = 0
        self.max_stall_ms = 0.0
        safety = config.safety
        self.feedback_timeout_s = safety.feedback_timeout_s
        self.command_timeout_s = safety.command_timeout_s
        self.fault_clear_s = safety.fault_clear_s
        self.joints: dict[str, _Joint] = {}
        # (bus, frame id) -> slot -> joint, for the DJI group frames
        self._dji_frames: dict[tuple[str, int], list[_Joint | None]] = {}
        self._mit_frames: dict[tuple[str, int], _Joint] = {}
        self._feedback: dict[tuple[str, int], list[_Joint]] = {}
        for jc in config.joints:
            actuator = actuator_class(jc.type)(jc, safety)
            joint = _Joint(actuator, safety.temperature_hysteresis_c, feedback_window_s)
            self.joints[jc.name] = joint
            if isinstance(actuator, DjiActuator):
                key = (jc.bus, actuator.command_frame_id)
                self._dji_frames.setdefault(key, [None] * dji.SLOTS_PER_FRAME)
                self._dji_frames[key][actuator.slot] = joint
            elif isinstance(actuator, MitActuator):
                self._mit_frames[(jc.bus, actuator.command_id)] = joint
            for fid in actuator.feedback_ids():
                self._feedback.setdefault((jc.bus, fid), []).append(joint)
        self._bus_of_channel = {str(b.channel): b.name for b in config.buses}
        self.violations: list[Violation] = []
        self.violation_count = 0
        self.frames = 0
        self.command_frames = 0
        self.system_frames = 0
        self.unmatched_frames = 0
        self.foreign_frames = 0

    # --- input -------------------------------------------------------------------------
    def bus_of_channel(self, channel: str) -> str:
        """The bus name of a python-can channel name (frames from a tap carry the channel)."""
        return self._bus_of_channel.get(str(channel), str(channel))

    def feed(self, bus: str, msg: can.Message, *, from_bridge: bool = True) -> list[Violation]:
        """Check one frame seen on ``bus`` at ``msg.timestamp`` [s]; return new violations.

        Args:
            bus: bus name.
            msg: the frame.
            from_bridge: False for a frame known to come from another node (a test's
                injected frame): it still counts as feedback if it has a feedback id (the
                bridge cannot tell either), but a command id is not judged as the bridge's.
        """
        self.frames += 1
        if msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
            return []
        t = float(msg.timestamp)
        key = (bus, msg.arbitration_id)
        data = bytes(msg.data)
        found: list[Violation] = []
        handled = False
        for joint in self._feedback.get(key, ()):
            handled = True
            self._on_feedback(joint, msg, t)
        if not from_bridge:
            self.foreign_frames += 1
            return []
        group = self._dji_frames.get(key)
        mit_joint = self._mit_frames.get(key)
        if group is not None or mit_joint is not None:
            handled = True
            td = self._decision_time(bus, t)
            if group is not None:
                self._check_dji(bus, msg.arbitration_id, group, data, t, td, found)
            if mit_joint is not None:
                self._check_mit(bus, msg.arbitration_id, mit_joint, data, t, td, found)
        if not handled:
            self.unmatched_frames += 1
        stall = self._last_stall.get(bus)
        if found and stall is not None and t - stall[0] <= self.stall_window_s:
            after = (1e3 * (t - stall[0]), stall[1])
            found = [dataclasses.replace(v, after_stall=after) for v in found]
        for v in found:
            self.violation_count += 1
            self.violations_by_rule[v.rule] = self.violations_by_rule.get(v.rule, 0) + 1
            if v.after_stall is not None:
                self.violations_after_stall += 1
            if len(self.violations) < self._keep:
                self.violations.append(v)
        return found

    def _decision_time(self, bus: str, t: float) -> float:
        """The latest time the bridge may have decided a command frame sent at ``t``.

        The scheduler decides a tick's frames, then sends them; if its process loses the
        CPU in between (a stall), the frames reach the wire late. After a gap longer than
        ``stall_s`` in the bridge's command frames on a bus, the frames of the first burst
        are judged at the gap's start plus one tick: what the bridge could know then.
        Stalls are counted (``stalls``, ``max_stall_ms``); the frames after the burst are
        judged at their own time again.
        """
        prev = self._last_tx.get(bus)
        self._last_tx[bus] = t
        if self.stall_s is None:
            return t
        burst = self._burst.get(bus)
        if burst is not None and t <= burst[0]:
            return burst[1]
        if prev is not None and t - prev > self.stall_s:
            self.stalls += 1
            self.max_stall_ms = max(self.max_stall_ms, 1e3 * (t - prev))
            self._last_stall[bus] = (t, 1e3 * (t - prev))
            decided = prev + self._tick_s
            self._burst[bus] = (t + _BURST_S, decided)
            return decided
        return t

    def feed_all(self, frames: Iterable[tuple[str, can.Message]]) -> list[Violation]:
        """Check ``(bus, frame)`` pairs in order; return the new violations."""
        out: list[Violation] = []
        for bus, msg in frames:
            out += self.feed(bus, msg)
        return out

    def note_fault(
        self, joint: str, kind: str, t: float, *, active: bool = True,
        temperature: float | None = None,
    ) -> None:
        """Record a fault injected into (``active``) or cleared from a motor at time t [s].

        ``kind`` is ``offline`` or ``over_temperature`` (the kinds that oblige zero output);
        an over-temperature below the joint's limit (a cooling motor) needs ``temperature``
        and counts as the fault cleared at t. Other kinds are accepted and not judged.
        """
        j = self.joints[joint]
        if kind == 'over_temperature' and active and temperature is not None:
            active = temperature >= j.temperature_limit
            if not active and 'over_temperature' not in j.injected:
                return  # cool from the start: nothing to latch
        if kind not in ('offline', 'over_temperature'):
            return
        if active:
            since, cleared = j.injected.get(kind, (t, None))
            j.injected[kind] = (since if cleared is None else t, None)
        elif kind in j.injected and j.injected[kind][1] is None:
            j.injected[kind] = (j.injected[kind][0], t)

    def note_command(self, msg: Any, t: float) -> None:
        """An rm_msgs/ActuatorCmd (or look-alike) the bridge received at wire time ``t`` [s].

        Only a message the bridge must apply counts: equal array lengths, known joints,
        no joint twice, known modes, finite values, gains >= 0, and a header stamp that is
        zero or within the command timeout (plus the grace) of ``t``. MODE_OFF ends a
        joint's command.
        """
        names = list(msg.name)
        columns = [list(getattr(msg, f)) for f in ('mode', 'position', 'velocity', 'effort')]
        columns += [list(msg.kp), list(msg.kd)]
        if any(len(c) != len(names) for c in columns) or len(set(names)) != len(names):
            return
        if any(n not in self.joints for n in names):
            return
        stamp = getattr(getattr(msg, 'header', None), 'stamp', None)
        if stamp is not None and (stamp.sec or stamp.nanosec):
            age = t - (stamp.sec + stamp.nanosec / _NS_PER_S)
            # near the limit the bridge (a callback earlier) may have taken it
            if abs(age) > self.command_timeout_s + self.grace_s:
                return
        modes, values = columns[0], columns[1:]
        for i in range(len(names)):
            if modes[i] not in tuple(Mode):
                return
            if not all(math.isfinite(float(c[i])) for c in values):
                return
            if values[3][i] < 0.0 or values[4][i] < 0.0:
                return
        for i, name in enumerate(names):
            self.note_joint_command(name, modes[i], t)

    def note_joint_command(self, joint: str, mode: int, t: float) -> None:
        """One joint's valid command, taken at wire time ``t`` [s] (e.g. observed where the
        bridge hands it to the hardware layer, after its own validation)."""
        j = self.joints.get(joint)
        if j is None:
            return
        j.commanded = True
        if mode == Mode.OFF:
            j.command_until = min(j.command_until, t)
        else:
            j.command_until = t + self.command_timeout_s

    # --- results -----------------------------------------------------------------------
    def timeline(self, joint: str) -> list[tuple[float, float, bool]]:
        """``(time [s], effort [N·m], non-zero)`` of every command to ``joint`` (``record``)."""
        return self.joints[joint].timeline

    def last_feedback(self, joint: str) -> float:
        """Wire time of the joint's latest decoded feedback frame [s] (-inf: none)."""
        return self.joints[joint].last_feedback()

    def stats(self, joint: str) -> JointStats:
        """What was seen of one joint."""
        return self.joints[joint].stats

    def summary(self) -> dict[str, Any]:
        """Counters for a report."""
        latencies = [x for j in self.joints.values() for x in j.stats.zero_latencies]
        return {
            'frames': self.frames,
            'command_frames': self.command_frames,
            'system_frames': self.system_frames,
            'unmatched_frames': self.unmatched_frames,
            'unsafe_frames': self.violation_count,
            'unsafe_by_rule': dict(self.violations_by_rule),
            'unsafe_after_stall': self.violations_after_stall,
            'stalls': self.stalls,
            'max_stall_ms': round(self.max_stall_ms, 1),
            'zero_episodes': len(latencies),
            'max_zero_latency_ms': round(1e3 * max(latencies), 1) if latencies else None,
            'max_effort_ratio': round(
                max(
                    (j.stats.max_effort_seen / j.max_effort for j in self.joints.values()),
                    default=0.0,
                ),
                3,
            ),
        }

    # --- feedback ------------------------------------------------------------------------
    def _on_feedback(self, joint: _Joint, msg: can.Message, t: float) -> None:
        shadow = joint.shadow
        before = shadow.frames_decoded
        try:
            claimed = shadow.handle_frame(msg, round(t * _NS_PER_S))
        except ProtocolError:
            return
        if not claimed or shadow.frames_decoded == before:
            return  # not this joint's (MIT id nibble) or did not decode
        fb = shadow.feedback
        joint.stats.feedback_frames += 1
        joint.last_feedback_t = t
        if isinstance(shadow, MitActuator):
            # what the motor itself reports (motor side, wrapped): its law uses these
            q, dq = _mit_reading(shadow, bytes(msg.data))
            joint.position.add(t, q)
            joint.velocity.add(t, dq)
        else:
            joint.velocity.add(t, fb.device_velocity)
        temperature = fb.temperature
        clear = self.fault_clear_s
        if temperature is not None:
            if temperature >= joint.temperature_limit:
                joint.cool_since = None
                if joint.overheated_since is None:
                    joint.overheated_since = t
            elif temperature < joint.temperature_resume:
                if joint.cool_since is None:
                    joint.cool_since = t
                if t - joint.cool_since >= clear:
                    joint.overheated_since = None
            else:
                joint.cool_since = None
        if fb.error_code and shadow._is_fault(fb.error_code):
            joint.fault_gone_since = None
            if joint.fault_since is None:
                joint.fault_since = t
        elif joint.fault_since is not None:
            if joint.fault_gone_since is None:
                joint.fault_gone_since = t
            if t - joint.fault_gone_since >= clear:
                joint.fault_since = None

    # --- commands ------------------------------------------------------------------------
    def _must_be_zero_since(self, joint: _Joint, t: float) -> tuple[float, str] | None:
        """When (and why) the joint had to be zero at ``t``, or None if it may be driven."""
        reasons: list[tuple[float, str]] = []
        last = joint.last_feedback()
        if t - last > self.feedback_timeout_s:
            reasons.append((last + self.feedback_timeout_s, 'offline'))
        # a fault's end is judged at t, with the grace: the bridge's clock and the wire's
        # may differ by a few ms about when the clear time ran out
        clear = self.fault_clear_s - self.grace_s
        if joint.overheated_since is not None and not (
                joint.cool_since is not None and t >= joint.cool_since + clear):
            reasons.append((joint.overheated_since, 'over_temperature'))
        if joint.fault_since is not None and not (
                joint.fault_gone_since is not None and t >= joint.fault_gone_since + clear):
            reasons.append((joint.fault_since, 'device_fault'))
        for kind, (since, cleared) in joint.injected.items():
            # offline: the bridge may drive until its feedback timeout; after either fault
            # it must wait fault_clear_s of good frames (offline: from the first one back)
            start = since + (self.feedback_timeout_s if kind == 'offline' else 0.0)
            end = math.inf
            if cleared is not None:
                if cleared < start:
                    continue  # back before the bridge could tell: no fault to clear
                end = cleared + self.fault_clear_s
            if start <= t < end:
                reasons.append((start, f'injected_{kind}'))
        if self.track_commands and joint.commanded and t > joint.command_until:
            reasons.append((joint.command_until, 'no_command'))
        if not reasons:
            return None
        return min(reasons)

    def _judge(
        self,
        joint: _Joint,
        bus: str,
        can_id: int,
        t: float,
        td: float,
        effort: float,
        nonzero: bool,
        limit_detail: str | None,
        found: list[Violation],
    ) -> None:
        stats = joint.stats
        stats.command_frames += 1
        stats.max_effort_seen = max(stats.max_effort_seen, abs(effort))
        if self._record:
            joint.timeline.append((t, effort, nonzero))
        if nonzero:
            stats.nonzero_frames += 1
        if limit_detail is not None:
            found.append(Violation(t, bus, can_id, joint.name, 'effort', limit_detail))
        must = self._must_be_zero_since(joint, td)
        if must is None:
            joint.episode_since = None
            return
        since, rule = must
        if joint.episode_since is None:
            joint.episode_since, joint.episode_zeroed = since, False
        if not nonzero:
            if not joint.episode_zeroed and math.isfinite(joint.episode_since):
                stats.zero_latencies.append(max(0.0, t - joint.episode_since))
            joint.episode_zeroed = True
            return
        late = td - since
        if late > self.grace_s:
            when = f'{late * 1e3:.1f} ms' if math.isfinite(late) else 'ever since start'
            if td != t:
                when += f' (decided by {1e3 * (t - td):.0f} ms before it was sent)'
            found.append(
                Violation(
                    t,
                    bus,
                    can_id,
                    joint.name,
                    rule,
                    f'effort {effort:+.4f} N·m asked {when} after the joint had to be zero '
                    f'({rule}; grace {self.grace_s * 1e3:.1f} ms)',
                )
            )

    def _check_dji(
        self,
        bus: str,
        can_id: int,
        group: list[_Joint | None],
        data: bytes,
        t: float,
        td: float,
        found: list[Violation],
    ) -> None:
        self.command_frames += 1
        try:
            raws = dji.unpack_command(data)
        except ProtocolError as err:
            found.append(Violation(t, bus, can_id, '', 'malformed', str(err)))
            return
        for slot, raw in enumerate(raws):
            joint = group[slot]
            if joint is None:
                if raw != 0:
                    found.append(
                        Violation(t, bus, can_id, '', 'unknown_slot', f'slot {slot} raw {raw}')
                    )
                continue
            shadow = joint.shadow
            assert isinstance(shadow, DjiActuator)
            spec = shadow.spec
            kt = shadow.torque_constant
            detail = None
            if abs(raw) > spec.raw_limit:
                detail = f'raw {raw} beyond the {spec.kind.value} limit ±{spec.raw_limit}'
            if raw == 0:
                # Zero drive. (For a GM6020 in voltage mode 0 V is a dynamic brake: the
                # back-EMF drives -Ke·ω/R through the windings, capped by the driver. It is
                # the bridge's hold output, and the only one that needs no fresh speed.)
                effort, step = 0.0, 0.0
            elif isinstance(shadow, Gm6020Voltage):
                effort, step = self._gm6020_effort(joint, shadow, raw, self._since(td, t))
            else:
                effort = raw * spec.si_per_raw * kt
                step = spec.si_per_raw * kt
            allowed = joint.max_effort + step + self.effort_tolerance
            if detail is None and abs(effort) > allowed:
                detail = f'raw {raw} = {effort:+.4f} N·m beyond max_effort {joint.max_effort} N·m'
            self._judge(joint, bus, can_id, t, td, effort, raw != 0, detail, found)

    def _since(self, td: float, t: float) -> float | None:
        """For a frame decided before it was sent (after a stall): the feedback window's
        start at the decision, else None."""
        return td - self.feedback_window_s if td < t else None

    @staticmethod
    def _gm6020_effort(
        joint: _Joint, shadow: Gm6020Voltage, raw: int, since: float | None = None
    ) -> tuple[float, float]:
        """Effort a GM6020 voltage command asks for, the smallest over the feedback window.

        The bridge computes the voltage with the newest feedback it has processed, which
        may be older than the newest on the wire (see ``feedback_window_s``); a frame
        decided before a stall, with any it had then (``since``).
        """
        volts = raw * shadow.spec.si_per_raw
        kt, r, ke = shadow.torque_constant, shadow.resistance, shadow.back_emf_constant
        bounds = joint.velocity.bounds(since) or (0.0, 0.0)
        # linear in ω: the extremes are at the window's bounds
        a, b = ((volts - ke * w) / r * kt for w in bounds)
        return _min_abs(min(a, b), max(a, b)), shadow.spec.si_per_raw / r * kt

    def _check_mit(
        self,
        bus: str,
        can_id: int,
        joint: _Joint,
        data: bytes,
        t: float,
        td: float,
        found: list[Violation],
    ) -> None:
        shadow = joint.shadow
        assert isinstance(shadow, MitActuator)
        try:
            if mit.parse_system_frame(data) is not None:
                self.system_frames += 1
                return
            cmd = mit.unpack_mit_command(data, shadow.limits)
        except ProtocolError as err:
            self.command_frames += 1
            found.append(Violation(t, bus, can_id, joint.name, 'malformed', str(err)))
            return
        self.command_frames += 1
        limits = shadow.limits
        t_step = 2.0 * limits.t_max / ((1 << mit.TORQUE_BITS) - 1)
        nonzero = cmd.kp > 0.0 or cmd.kd > 0.0 or abs(cmd.torque) > t_step
        g = shadow.gear_ratio
        # the torque the motor applies, the smallest over the feedback window (linear in
        # q and dq: the extremes are at the window's bounds)
        since = self._since(td, t)
        q_lo, q_hi = joint.position.bounds(since) or (0.0, 0.0)
        dq_lo, dq_hi = joint.velocity.bounds(since) or (0.0, 0.0)
        lo = cmd.kp * (cmd.position - q_hi) + cmd.kd * (cmd.velocity - dq_hi) + cmd.torque
        hi = cmd.kp * (cmd.position - q_lo) + cmd.kd * (cmd.velocity - dq_lo) + cmd.torque
        effort = _min_abs(lo, hi) * g
        # quantisation of p, v, kp, kd and tau, at this command's size
        p_step = 2.0 * limits.p_max / ((1 << mit.POSITION_BITS) - 1)
        v_step = 2.0 * limits.v_max / ((1 << mit.VELOCITY_BITS) - 1)
        kp_step = (limits.kp_max - limits.kp_min) / ((1 << mit.KP_BITS) - 1)
        kd_step = (limits.kd_max - limits.kd_min) / ((1 << mit.KD_BITS) - 1)
        q = joint.position.last if joint.position.bounds() else 0.0
        dq = joint.velocity.last if joint.velocity.bounds() else 0.0
        step = g * (
            t_step
            + cmd.kp * p_step
            + cmd.kd * v_step
            + kp_step * abs(cmd.position - q)
            + kd_step * abs(cmd.velocity - dq)
        )
        detail = None
        if abs(effort) > joint.max_effort + step + self.effort_tolerance:
            detail = (
                f'MIT kp {cmd.kp:.3f} kd {cmd.kd:.3f} p {cmd.position:+.3f} v {cmd.velocity:+.3f} '
                f'tau {cmd.torque:+.3f} = {effort:+.4f} N·m beyond max_effort {joint.max_effort}'
            )
        self._judge(joint, bus, can_id, t, td, effort if nonzero else 0.0, nonzero, detail, found)


def _mit_reading(shadow: MitActuator, data: bytes) -> tuple[float, float]:
    """Position [rad] and velocity [rad/s] as the MIT motor reports them (motor side)."""
    if isinstance(shadow, Cheetah):
        reply = cheetah.decode_reply(data, shadow.limits)
        return reply.position, reply.velocity
    fb = damiao.decode_feedback(data, shadow.limits)
    return fb.position, fb.velocity


def check_actuator_states(msg: Any, limits: Mapping[str, float]) -> list[str]:
    """Problems in one rm_msgs/ActuatorState: NaN/inf commands, beyond the limits, or a
    held joint (MODE_OFF) with a non-zero command.

    Args:
        msg: the message.
        limits: joint -> max_effort [N·m].
    """
    problems = []
    modes = list(msg.mode)
    for i, name in enumerate(msg.name):
        command = float(msg.command[i])
        if not math.isfinite(command):
            problems.append(f'{name}: command {command}')
            continue
        limit = limits.get(name)
        if limit is not None and abs(command) > limit * (1 + 1e-6) + 1e-3:
            problems.append(f'{name}: command {command:+.4f} beyond {limit}')
        if modes and modes[i] == Mode.OFF and command != 0.0:
            problems.append(f'{name}: MODE_OFF with command {command:+.4f}')
    return problems


def max_efforts(config: Mapping[str, Any] | HardwareConfig) -> dict[str, float]:
    """joint -> resolved max_effort [N·m] (type defaults filled in) of a hardware config."""
    if not isinstance(config, HardwareConfig):
        config = HardwareConfig.from_dict(config)
    return {jc.name: actuator_class(jc.type)(jc, config.safety).max_effort for jc in config.joints}
