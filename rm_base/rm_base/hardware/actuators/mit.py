"""MIT-mode motors: the base of the Damiao and MIT Cheetah families (rm_base/motors/).

Each motor has its own command frame (id = motor id). ``MODE_MIT`` is passed through
natively (the motor closes ``kp``/``kd`` itself at its own rate); the other modes send a
pure-torque MIT frame (kp = kd = 0) carrying the effort computed on the host. A held
joint gets an all-zero-gain, zero-torque frame: limp.

Because the motor evaluates ``kp·(p − q) + kd·(v − dq) + τ`` itself, the effort limit is
enforced by moving the targets: when the host's estimate of that law (from the latest
feedback, with kp/kd saturated at the motor's ranges as the frame will carry them) exceeds
``max_effort``, the position target (or, with kp = 0, the velocity target) is shifted so
the estimate equals the limit. Should the shifted target lie outside the frame's ranges
(so the motor would not hold the limit), a pure-torque frame at the limit goes instead.

Family options (``joints.<name>.<key>``):

* ``model`` (Damiao): see rm_base/motors/damiao/actuator.py;
* ``limits``: overrides of the MIT ranges (``p_max``, ``v_max``, ``t_max``, ``kp_max``,
  ``kd_max``...) — they must equal the motor's registers (Damiao RID 21–23);
* ``master_id``: CAN id the motor replies on (Damiao MST_ID register: default id + 0x10,
  a common convention — set it to the motor's value; Cheetah CAN_MASTER: default 0).
  Replies are matched by the id in byte 0, so motors may share a master id;
* ``auto_enable`` (default True): send ENABLE at start, when a Damiao reports itself
  disabled (at most every 100 ms), and when a motor comes back online;
* ``disable_on_shutdown`` (default True): send DISABLE after the final zero frame.

The Damiao position is assumed to wrap over ±PMAX (UNVERIFIED; a wrap can't be confused
with motion at 1 kHz) and is unwrapped into a continuous position.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import can

from rm_base.config.schema import Schema, boolean, integer, mapping
from rm_base.hardware.actuators.base import (
    Actuator,
    Feedback,
    JointCommand,
    Unwrapper,
)
from rm_base.hardware.config import JointConfig, SafetyConfig
from rm_base.hardware.errors import HardwareConfigError
from rm_base.hardware.protocols import mit
from rm_base.hardware.protocols.mit import MitCommand, MitLimits, SystemCommand
from rm_base.joints import Mode

#: Minimum time between automatic ENABLE frames [ns].
ENABLE_RETRY_NS = 100_000_000
_ZERO = MitCommand(0.0, 0.0, 0.0, 0.0, 0.0)


#: A joint's (and a simulated motor's) ``limits`` option: MIT ranges over the defaults.
LIMITS_KEY = mapping('limits', None,
                     description="MIT ranges over the model's (p_min, p_max, v_max, t_max...)")


def limits_from_config(
    name: str, base: MitLimits, overrides: Mapping[str, Any] | None
) -> MitLimits:
    """Apply a joint's ``limits`` overrides (read by ``LIMITS_KEY``) to ``base``.

    Raises:
        HardwareConfigError: an unknown or invalid field.
    """
    try:
        return base.with_overrides(overrides)
    except HardwareConfigError as err:
        raise HardwareConfigError(f'joints.{name}.limits: {err}') from err


def fit_mit_target(
    kp: float, kd: float, p: float, v: float, ff: float, *, q: float, dq: float, effort: float
) -> tuple[float, float, float]:
    """Move an MIT target so that ``kp(p - q) + kd(v - dq) + ff`` is effort at (q, dq).

    The position moves if there is a stiffness, else the velocity if there is a damping,
    else the feed-forward becomes effort: the motor's own law then applies the (clamped)
    effort now and keeps the gains' behaviour around it.

    Returns:
        The new (position, velocity, feed-forward).
    """
    excess = kp * (p - q) + kd * (v - dq) + ff - effort
    if excess != 0.0:
        if kp > 0.0:
            p -= excess / kp
        elif kd > 0.0:
            v -= excess / kd
        else:
            ff = effort
    return p, v, ff


def _sat(x: float, limit: float) -> float:
    return limit if x > limit else -limit if x < -limit else x


class MitActuator(Actuator):
    """Shared MIT frame handling for Damiao and Cheetah; subclasses decode replies."""

    options_schema = Schema((
        LIMITS_KEY,
        integer('master_id', None, ge=0, le=0x7FF,
                description="id the motor replies on; default the family's"),
        boolean('auto_enable', True, description='send enable when the motor comes online'),
        boolean('disable_on_shutdown', True, description='send disable when the bridge stops'),
    ))
    max_motor_id: ClassVar[int] = 0x7FF

    def __init__(
        self, config: JointConfig, limits: MitLimits, safety: SafetyConfig | None = None
    ) -> None:
        """Build the actuator (``limits`` already resolved by the subclass).

        Raises:
            HardwareConfigError: invalid id or option.
        """
        super().__init__(config, safety)
        if not 0 <= config.id <= self.max_motor_id:
            raise HardwareConfigError(
                f'joints.{config.name}.id {config.id} outside 0..{self.max_motor_id}'
            )
        opts = self.options
        master = opts['master_id']
        if master is None:
            master = self._default_master_id(config.id)
        self.limits = limits
        self.motor_id = config.id
        #: Command frame id (the motor id; MIT mode has no offset).
        self.command_id = config.id
        self.master_id = master
        self.auto_enable: bool = opts['auto_enable']
        self.disable_on_shutdown: bool = opts['disable_on_shutdown']
        self._position_unwrapper = Unwrapper(2.0 * limits.p_max)
        self._fields = _ZERO
        self._system_pending: SystemCommand | None = (
            SystemCommand.ENABLE if self.auto_enable else None
        )
        self._last_enable_ns: int | None = None
        self._was_online = False
        self.system_frames_sent = 0

    @staticmethod
    def _default_master_id(motor_id: int) -> int:
        return 0

    # --- hooks shared by the MIT families ---
    def _feedback_ids(self) -> tuple[int, ...]:
        return (self.master_id,)

    def _set_output(self, effort: float, command: JointCommand, feedback: Feedback) -> float:
        d, g = self.direction, self.gear_ratio
        if command.mode is not Mode.MIT:
            self._fields = MitCommand(0.0, 0.0, 0.0, 0.0, d * effort / g)
            return effort
        lim, g2 = self.limits, g * g
        # The gains the motor will really use: the frame saturates them at its ranges. The
        # clamp below must be computed with those, or it shifts the target for gains the
        # motor never sees (kp 1e9 -> 500: thousands of N·m asked).
        kp = min(max(command.kp, lim.kp_min * g2), lim.kp_max * g2)
        kd = min(max(command.kd, lim.kd_min * g2), lim.kd_max * g2)
        p, v, ff = command.position, command.velocity, command.effort
        q, dq = feedback.position, feedback.velocity
        estimate = kp * (p - q) + kd * (v - dq) + ff
        target = max(-self.max_effort, min(self.max_effort, estimate))
        p, v, ff = fit_mit_target(kp, kd, p, v, ff, q=q, dq=dq, effort=target)
        # joint -> motor shaft, then back into the motor's wrapped position range
        span_turns = self._position_unwrapper.turns * 2.0 * lim.p_max
        to_dev = g * (d * (p - self._turn_shift) + self.zero_offset) - span_turns
        q_dev = g * (d * (q - self._turn_shift) + self.zero_offset) - span_turns
        fields = MitCommand(to_dev, d * v * g, kp / g2, kd / g2, d * ff / g)
        # What the motor applies once the frame saturates p, v and tau at their ranges; a
        # shifted target outside them (a large kd·velocity error with a small kp) would
        # not hold the limit: then send the limit as a pure torque instead.
        torque_dev = (
            fields.kp * (_sat(fields.position, lim.p_max) - q_dev)
            + fields.kd * (_sat(fields.velocity, lim.v_max) - d * dq * g)
            + _sat(fields.torque, lim.t_max)
        )
        applied = d * g * torque_dev
        if abs(applied) > self.max_effort * (1.0 + 1e-9) + 1e-12:
            fields = MitCommand(0.0, 0.0, 0.0, 0.0, d * target / g)
            applied = target
        self._fields = fields
        return applied

    def _set_zero_output(self) -> None:
        self._fields = _ZERO

    def _after_update(self, now_ns: int) -> None:
        online = self._online
        if not self.auto_enable or self._shutdown:
            self._was_online = online
            return
        came_back = online and not self._was_online and self._last_enable_ns is not None
        self._was_online = online
        if came_back or (online and self._reports_disabled()):
            last = self._last_enable_ns
            if last is None or now_ns - last >= ENABLE_RETRY_NS:
                self._system_pending = SystemCommand.ENABLE
        if self._system_pending is SystemCommand.ENABLE:
            self._last_enable_ns = now_ns

    def _reports_disabled(self) -> bool:
        return False

    def _system_data(self, command: SystemCommand) -> bytes:
        return mit.system_frame(command)

    def _pack(self) -> can.Message:
        pending = self._system_pending
        if pending is not None and not self._shutdown:
            self._system_pending = None
            self.system_frames_sent += 1
            data = self._system_data(pending)
            if pending is SystemCommand.SET_ZERO:  # frames after this one read from 0
                self._pending_zero = (0.0, 0.0)
        else:
            data = mit.pack_mit_command(self._fields, self.limits)
        return can.Message(arbitration_id=self.motor_id, data=data, is_extended_id=False)

    # --- public extras ---
    def request_system_command(self, command: SystemCommand | int) -> None:
        """Send a system frame (enable, disable, set zero, clear error) at the next tick.

        It replaces that tick's command frame.

        Raises:
            ValueRangeError: the family does not know the command.
        """
        command = SystemCommand(command)
        self._system_data(command)  # validates for this family
        self._system_pending = command

    def zero_here(self) -> float:
        """Make the present position the zero: the motor's own set-zero (SET_ZERO frame).

        The motor keeps that zero itself (Damiao: in its flash), so the joint's
        ``zero_offset`` becomes 0 from the first frame after it.

        Raises:
            ValueRangeError: the family has no set-zero command.
        """
        self.request_system_command(SystemCommand.SET_ZERO)
        return 0.0

    def final_frames(self) -> list[can.Message]:
        """Frames to send after the final zero command at shutdown (DISABLE)."""
        if not self.disable_on_shutdown:
            return []
        return [
            can.Message(
                arbitration_id=self.motor_id,
                data=self._system_data(SystemCommand.DISABLE),
                is_extended_id=False,
            )
        ]

    @property
    def mit_fields(self) -> MitCommand:
        """The MIT command (motor side) packed at the next tick."""
        return self._fields
