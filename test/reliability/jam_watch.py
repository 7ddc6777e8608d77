"""JamWatch: whether a jam on a joint (not the trigger) showed, for the soak.

A jammed joint shows as its output at the clamp: its own loop pushes against the stall and
the safety clamp holds it there. That happens only when the joint is asked for enough. A
velocity loop holding a stalled rotor pushes at most kp * |speed asked| plus its wound-up
integral term, so a slower target never reaches the clamp, however long the jam lasts: a
gimbal that holds its aim next to where its yaw jammed asks the yaw for a few hundredths of
a rad/s (docs/RELIABILITY.md, "Jams the robot cannot show"). The watch works out, from the
joint's command and its loop's gains, the most the joint's loop would push against a stall,
and judges the jam only if that reaches the clamp. A joint of a power-limited group (the
wheels) shows at the clamp times the factor the group's power stage applied: the limit
comes first, as in the firmware.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rm_base.geometry.angles import wrap_to_pi
from rm_base.joints import Mode

#: The share of the clamp that counts as at the clamp.
AT_CLAMP = 0.99


def stall_push(gains: Any, speed: float) -> float:
    """The most a velocity loop (``PidGains``) pushes a stalled rotor asked for speed [rad/s].

    Its proportional term plus its integral term wound up to the integral limit; a loop
    that integrates only small errors (``integral_separation``) adds none for a larger one.
    """
    integrates = gains.ki > 0.0 and abs(speed) < gains.integral_separation
    integral = min(gains.integral_limit, gains.output_limit) if integrates else 0.0
    return float(min(gains.kp * abs(speed) + integral, gains.output_limit))


def stall_demand(actuator: Any, command: Any, position: float) -> float:
    """The most the joint's loop pushes against a stall under command [N·m], unclamped.

    Args:
        actuator: an ``Actuator`` (its config's velocity and position PID gains, max_velocity).
        command: its latest ``JointCommand``, or None.
        position: where the joint stands [rad].
    """
    if command is None:
        return 0.0
    mode = command.mode
    if mode == Mode.EFFORT:
        return float(abs(command.effort))
    if mode == Mode.MIT:  # stalled: no velocity
        return float(abs(
            command.kp * (command.position - position) + command.kd * command.velocity
            + command.effort
        ))
    if mode == Mode.VELOCITY:
        speed = command.velocity
    elif mode == Mode.POSITION:  # the outer loop's proportional answer, as the actuator's
        gains = actuator.config.position_pid
        error = command.position - position
        speed = gains.kp * (wrap_to_pi(error) if gains.angle_mode else error) + command.velocity
    else:
        return 0.0
    speed = max(-actuator.max_velocity, min(actuator.max_velocity, speed))
    return stall_push(actuator.config.velocity_pid, speed)


class JamWatch:
    """Samples one jammed joint; says whether the jam showed and whether it could.

    Args:
        actuator: the jammed joint's ``Actuator`` (``state()``, ``command``, ``max_effort``).
        power_scale: the factor the power stage of the joint's group applied at the last
            tick (1.0 when it scaled nothing); None: the joint has no power limit.
    """

    def __init__(self, actuator: Any, power_scale: Callable[[], float] | None = None) -> None:
        self.actuator = actuator
        self.power_scale = power_scale
        self.clamp = float(actuator.max_effort)
        self.least_scale = 1.0  # the power stage's smallest factor seen
        self.peak_output = 0.0  # largest |output| seen [N·m]
        self.peak_demand = 0.0  # largest stall push its commands asked for [N·m]
        self.modes: set[int] = set()

    def sample(self) -> bool:
        """Take one sample; return whether the output is at its clamp (the jam showed)."""
        state = self.actuator.state()
        scale = 1.0 if self.power_scale is None else min(1.0, self.power_scale())
        self.least_scale = min(self.least_scale, scale)
        output = abs(state.command)
        self.peak_output = max(self.peak_output, output)
        self.modes.add(int(state.mode))
        if state.mode != Mode.OFF:  # a joint held safe asks for nothing
            demand = stall_demand(self.actuator, self.actuator.command, state.position)
            self.peak_demand = max(self.peak_demand, demand)
        return output >= AT_CLAMP * self.clamp * scale

    @property
    def judged(self) -> bool:
        """Whether the joint was asked for enough that a jam must reach its clamp."""
        return self.peak_demand >= AT_CLAMP * self.clamp

    def note(self) -> str:
        """What the samples showed, as shares of the clamp."""
        return (
            f'output peaked at {self.peak_output / self.clamp:.0%} of its clamp, its commands '
            f'asked a stalled loop for up to {self.peak_demand / self.clamp:.0%}, '
            f'modes {sorted(self.modes)}, least power factor {self.least_scale:.2f}'
        )


def power_scale(hardware: Any, joint: str) -> Callable[[], float] | None:
    """The factor of the power stage whose group holds joint (``CanHardware``), or None."""
    for stage in hardware.power_limits.values():
        if joint in stage.joints:
            def scale(stage: Any = stage) -> float:
                last = stage.last  # once: the loop replaces it each tick
                return 1.0 if last is None else float(last.scale)
            return scale
    return None


class FeedSpan:
    """The longest the shooter pushed its trigger while feeding (FEED or PUSH), unbroken.

    A jammed trigger shows only once it stalled, pushed harder than the jam effort, for
    the shooter's jam time while feeding. A feed that ended sooner (the last step of a
    burst), or one that waited for the friction wheels with the trigger at rest, cannot
    show it.

    Args:
        effort_threshold: the shooter's jam effort (``shooter.jam.effort``) [N·m].
    """

    def __init__(self, effort_threshold: float) -> None:
        self.effort_threshold = effort_threshold
        self._fed_since: float | None = None
        self._pushed_since: float | None = None
        self.longest_fed = 0.0  # [s] fed, pushing or not
        self.longest = 0.0  # [s] fed and pushed past the jam effort

    def sample(self, feeding: bool, effort: float, now: float) -> None:
        """One sample at now [s]: whether the shooter fed, and the trigger's effort [N·m]."""
        if not feeding:
            self._fed_since = self._pushed_since = None
            return
        if self._fed_since is None:
            self._fed_since = now
        self.longest_fed = max(self.longest_fed, now - self._fed_since)
        if abs(effort) <= self.effort_threshold:
            self._pushed_since = None
            return
        if self._pushed_since is None:
            self._pushed_since = now
        self.longest = max(self.longest, now - self._pushed_since)
