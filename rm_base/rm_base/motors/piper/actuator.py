"""AgileX Piper arm joints driven by per-joint MIT frames (0x15A..0x15F).

``MODE_MIT`` is passed through natively; the other modes send a pure-torque frame
(kp = kd = 0). State comes from the arm's joint angle frames (0x2A5..0x2A7, 0.001°) and
the driver high-speed feedback (0x251..0x256: velocity, current; effort = current ×
the SDK's per-joint coefficient). Those feedback layouts are from piper_sdk docstrings,
not docs/PROTOCOLS.md (UNVERIFIED on an arm).

This layer does not run the arm's own enable / mode sequence (EnablePiper, MotionCtrl_2
with MIT mode 0xAD); the arm must be put into MIT mode first.

Family options: ``limits`` (overrides of the SDK's fixed ranges) and ``torque_range``, the
torque the 8-bit field spans: 18 (N·m, the default) or 8. Firmware decodes one or the
other and which one an arm runs is not known from here: a ±18 encoding read as ±8 asks
0.44 x the torque, a ±8 encoding read as ±18 asks 2.25 x, so the default is the one that
can never ask more than the joint was commanded (docs/PROTOCOLS.md §3).
"""

from __future__ import annotations

import can

from rm_base.config.schema import Schema, one_of
from rm_base.hardware.actuators.base import Actuator, Defaults, Feedback, JointCommand
from rm_base.hardware.actuators.mit import LIMITS_KEY, fit_mit_target, limits_from_config
from rm_base.hardware.config import JointConfig, SafetyConfig
from rm_base.hardware.errors import HardwareConfigError
from rm_base.hardware.protocols.mit import MitCommand
from rm_base.joints import Mode
from rm_base.motors.piper import protocol as piper

_ZERO = MitCommand(0.0, 0.0, 0.0, 0.0, 0.0)
#: torque_range [N·m] -> the command ranges with that torque encoding
_TORQUE_RANGES = {18: piper.PIPER_MIT_LIMITS_LEGACY, 8: piper.PIPER_MIT_LIMITS}


class PiperJoint(Actuator):
    """One Piper joint (``id`` = joint number 1..6)."""

    type_name = 'piper'
    options_schema = Schema((
        LIMITS_KEY,
        one_of('torque_range', (18, 8), 18,
               description="t_ref range [N·m] the arm's firmware decodes: 18 (official SDK) "
               'or 8 (newer firmware)'),
    ))

    def __init__(self, config: JointConfig, safety: SafetyConfig | None = None) -> None:
        """Build the joint.

        Raises:
            HardwareConfigError: joint id outside 1..6 or an invalid option.
        """
        if not 1 <= config.id <= piper.JOINT_COUNT:
            raise HardwareConfigError(f'joints.{config.name}.id must be a Piper joint 1..6')
        if config.gear_ratio not in (None, 1.0):
            raise HardwareConfigError(f'joints.{config.name}.gear_ratio: Piper joints are 1:1')
        options = self.read_options(config)
        base = _TORQUE_RANGES[options['torque_range']]
        self.torque_range = float(options['torque_range'])
        self.limits = limits_from_config(config.name, base, options['limits'])
        kt = piper.EFFORT_PER_AMP[config.id - 1]
        self.defaults = Defaults(1.0, kt, self.limits.t_max, self.limits.v_max, 80.0)
        super().__init__(config, safety)
        self._kt = self._current_kt()
        self.joint = config.id
        self.command_id = piper.joint_command_id(config.id)
        self._angle_id, self._angle_index = piper.joint_feedback_id(config.id)
        self._speed_id = piper.HIGH_SPEED_FEEDBACK_BASE_ID + config.id - 1
        self._angle = 0.0
        self._velocity = 0.0
        self._torque = 0.0
        self._fields = _ZERO

    def _feedback_ids(self) -> tuple[int, ...]:
        return (self._angle_id, self._speed_id)

    def details(self) -> dict[str, str | float]:
        """The torque encoding: which firmware this joint assumes."""
        return {'torque_range [N*m]': self.torque_range}

    def _decode(self, msg: can.Message) -> tuple[float, float, float, float | None, int]:
        if msg.arbitration_id == self._angle_id:
            _, a, b = piper.decode_joint_feedback(msg.arbitration_id, msg.data)
            self._angle = b if self._angle_index else a
        else:
            _, velocity, current, _ = piper.decode_high_speed_feedback(msg.arbitration_id, msg.data)
            self._velocity = velocity
            self._torque = current * self._kt
        return self._angle, self._velocity, self._torque, None, 0

    def _set_output(self, effort: float, command: JointCommand, feedback: Feedback) -> float:
        d = self.direction
        if command.mode is not Mode.MIT:
            self._fields = MitCommand(0.0, 0.0, 0.0, 0.0, d * effort)
            return effort
        kp, kd = command.kp, command.kd
        p, v, ff = fit_mit_target(
            kp, kd, command.position, command.velocity, command.effort,
            q=feedback.position, dq=feedback.velocity, effort=effort,
        )
        self._fields = MitCommand(d * p + self.zero_offset, d * v, kp, kd, d * ff)
        return effort

    def _set_zero_output(self) -> None:
        self._fields = _ZERO

    def _pack(self) -> can.Message:
        can_id, data = piper.pack_joint_mit(self.joint, self._fields, self.limits)
        return can.Message(arbitration_id=can_id, data=data, is_extended_id=False)

    @property
    def mit_fields(self) -> MitCommand:
        """The MIT command (arm side) packed at the next tick."""
        return self._fields
