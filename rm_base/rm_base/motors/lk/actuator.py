"""LK-TECH MF/MG motors on their torque command (0xA1), the robot's own loops around it.

Each tick the joint sends 0xA1 with the iq its effort asks (the family's current scale)
to 0x140 + id; the reply carries temperature, iq, rotor speed and the single-turn rotor
encoder, unwrapped here to a multi-turn position as a DJI rotor's is. Every
``status_period`` one tick's frame is the status-1 read (0x9A) instead: supply voltage,
motor on/off and the error bits (under-voltage, over-temperature), which become the
joint's device fault until the motor reports none (the base's latch clears it on
evidence). The motor keeps its previous torque through that millisecond; a step to zero
output is never delayed by a status read. A motor that reports itself off is sent RUN
(0x88), at most every 100 ms; the bridge's stop sends STOP (0x81).

The motor's own speed and position loops (0xA2..0xA8) are in ``protocol`` for tools
and the simulator; the joint does not use them, since its ``max_effort`` could not be
held through them (docs/PROTOCOLS.md §2.8).
"""

from __future__ import annotations

import math
from typing import ClassVar

import can

from rm_base.config.schema import Schema, boolean, integer, number, string
from rm_base.geometry.encoder import EncoderUnwrapper
from rm_base.hardware.actuators.base import Actuator, Defaults, Feedback, JointCommand
from rm_base.hardware.config import JointConfig, SafetyConfig
from rm_base.hardware.errors import HardwareConfigError, ValueRangeError
from rm_base.motors.lk import protocol as lk

_DPS = math.pi / 180.0
#: Fewest nanoseconds between two RUN frames to a motor that says it is off.
RUN_RETRY_NS = 100_000_000


class LkModel:
    """What a model brings: series (current scale), gear, catalogue defaults."""

    __slots__ = ('defaults', 'encoder_bits', 'series')

    def __init__(self, series: str, encoder_bits: int, defaults: Defaults) -> None:
        self.series = series
        self.encoder_bits = encoder_bits
        self.defaults = defaults


#: Order-of-magnitude catalogue values (docs/PROTOCOLS.md §2.8): gear, Kt at the output
#: [N·m/A], max effort [N·m], no-load speed [rad/s], temperature limit [°C].
MODELS: dict[str, LkModel] = {
    'MF9025': LkModel('mf', 16, Defaults(1.0, 0.32, 5.0, 35.0, 80.0)),
    'MG4010': LkModel('mg', 16, Defaults(10.0, 0.7, 4.5, 13.0, 80.0)),
}


class LkActuator(Actuator):
    """An LK motor on 0xA1 torque commands."""

    type_name = 'lk'
    default_model: ClassVar[str | None] = None
    start_near_zero = True
    options_schema = Schema((
        string('model', None, nonempty=True,
               description=f'{", ".join(MODELS)}: its defaults; type lk must set it or '
               'current_scale'),
        string('current_scale', None, choices=tuple(lk.CURRENT_SCALES),
               description="iq's amperes: mf, mg (protocol V2.35) or v2.3; default the "
               "model's series"),
        integer('encoder_bits', None, ge=14, le=16,
                description="the encoder's width as the reply carries it; default the "
                "model's (16)"),
        number('status_period', 0.1, unit='s', gt=0.0,
               description='how often a status read (voltage, error bits) replaces the '
               'torque frame'),
        boolean('auto_run', True, description='send RUN when the motor says it is off'),
        boolean('stop_on_shutdown', True, description='send STOP when the bridge stops'),
    ))

    def __init__(self, config: JointConfig, safety: SafetyConfig | None = None) -> None:
        """Build the actuator; see the module docstring for the options.

        Raises:
            HardwareConfigError: unknown model, invalid id or option.
        """
        options = self.read_options(config)
        where = f'joints.{config.name}'
        name = options['model'] or self.default_model
        model = MODELS.get(name.upper()) if name is not None else None
        if name is not None and model is None:
            raise HardwareConfigError(f'{where}.model {name!r}: one of {", ".join(MODELS)}')
        scale = options['current_scale'] or (model.series if model else None)
        if scale is None:
            raise HardwareConfigError(
                f'{where}: type {self.type_name!r} needs model ({", ".join(MODELS)}) or '
                'current_scale with gear_ratio, torque_constant, max_effort, max_velocity')
        if model is not None:
            self.defaults = model.defaults
        else:
            missing = [k for k in ('gear_ratio', 'torque_constant', 'max_effort',
                                   'max_velocity') if getattr(config, k) is None]
            if missing:
                raise HardwareConfigError(
                    f'{where}: without a model, set {", ".join(missing)}')
            self.defaults = Defaults(1.0, 1.0, 1.0, 1.0, 80.0)  # all overridden by config
        super().__init__(config, safety)
        try:
            self.command_id = lk.motor_frame_id(config.id)
        except ValueRangeError as err:
            raise HardwareConfigError(f'{where}.id: {err}') from err
        self.scale = lk.CURRENT_SCALES[scale]
        bits = options['encoder_bits'] or (model.encoder_bits if model else 16)
        self._unwrapper = EncoderUnwrapper(1 << bits)
        self._kt = self._current_kt()
        self._kt_rotor = self._kt / self.gear_ratio
        self._status_period_ns = round(options['status_period'] * 1e9)
        self.auto_run: bool = options['auto_run']
        self.stop_on_shutdown: bool = options['stop_on_shutdown']
        #: iq [LSB] packed at the next tick.
        self.iq = 0
        self._sent_iq = 0
        self._next_status_ns: int | None = None
        self._status_due = False
        self._run_due = False
        self._last_run_ns: int | None = None
        # from the latest status reply (receive thread; one assignment each)
        self.error_state = 0
        self.motor_on: bool | None = None
        self.voltage: float | None = None
        self.status_frames = 0
        #: Frames of this motor taken, of every kind (motion, status, echo).
        self.replies = 0

    # --- hooks ---
    def _feedback_ids(self) -> tuple[int, ...]:
        return (self.command_id,)

    def _match(self, msg: can.Message) -> bool:
        return len(msg.data) > 0 and msg.data[0] in lk.MOTION_REPLIES

    def handle_frame(self, msg: can.Message, now_ns: int) -> bool:
        """As for every actuator; status and echo replies update the motor's state."""
        data = msg.data
        if len(data) == lk.FRAME_LENGTH and data[0] in lk.STATUS_REPLIES:
            status = lk.decode_status_1(data)
            self.voltage = status.voltage_v
            self.motor_on = status.motor_on
            self.error_state = status.error
            self.status_frames += 1
            claimed = True
        elif len(data) > 0 and data[0] in lk.ECHO_REPLIES:
            claimed = True
        else:
            claimed = super().handle_frame(msg, now_ns)
        if claimed:
            self.replies += 1
        return claimed

    def _decode(self, msg: can.Message) -> tuple[float, float, float, float | None, int]:
        reply = lk.decode_motion_reply(msg.data)
        angle = self._unwrapper.update(reply.encoder)
        torque = reply.iq * self.scale.reply_amps * self._kt_rotor
        return (angle, reply.speed_dps * _DPS, torque, float(reply.temperature_c),
                self.error_state)

    def _set_output(self, effort: float, command: JointCommand, feedback: Feedback) -> float:
        amps = self.direction * effort / self._kt
        limit = self.scale.command_limit
        iq = max(-limit, min(limit, round(amps / self.scale.command_amps)))
        self.iq = iq
        return self.direction * iq * self.scale.command_amps * self._kt

    def _set_zero_output(self) -> None:
        self.iq = 0

    def _after_update(self, now_ns: int) -> None:
        due = self._next_status_ns
        if due is None or now_ns >= due:
            self._status_due = True
            self._next_status_ns = now_ns + self._status_period_ns
        if self.auto_run and not self._shutdown and self.motor_on is False:
            last = self._last_run_ns
            if last is None or now_ns - last >= RUN_RETRY_NS:
                self._run_due = True
                self._last_run_ns = now_ns

    def _pack(self) -> can.Message:
        iq = self.iq
        # a read takes the tick's place only when it delays no step to zero output
        may_read = iq != 0 or self._sent_iq == 0
        if may_read and self._run_due:
            self._run_due = False
            data = lk.pack_simple(lk.Command.RUN)
        elif may_read and self._status_due:
            self._status_due = False
            data = lk.pack_simple(lk.Command.READ_STATUS_1)
        else:
            self._sent_iq = iq
            data = lk.pack_torque(iq, self.scale)
        return can.Message(arbitration_id=self.command_id, data=data, is_extended_id=False)

    def final_frames(self) -> list[can.Message]:
        """STOP after the final zero torque, if ``stop_on_shutdown``."""
        if not self.stop_on_shutdown:
            return []
        return [can.Message(arbitration_id=self.command_id,
                            data=lk.pack_simple(lk.Command.STOP), is_extended_id=False)]

    def zero_here(self) -> float:
        """Make the present position the zero (an offset), at a direct drive only.

        Raises:
            CommandRejectedError: geared, or no feedback yet.
        """
        return self._zero_at_direct_drive()

    def details(self) -> dict[str, str | float]:
        """The base's details, and what the last status read said."""
        out = super().details()
        if self.voltage is not None:
            out['supply_voltage'] = self.voltage
        out['motor_on'] = str(self.motor_on)
        out['lk_error'] = lk.error_names(self.error_state)
        return out


class Mf9025(LkActuator):
    """MF9025 (direct drive, V2.35 MF scale ±16.5 A)."""

    type_name = 'mf9025'
    default_model = 'MF9025'


class Mg4010(LkActuator):
    """MG4010E-i10 (10:1, V2.35 MG scale ±33 A)."""

    type_name = 'mg4010'
    default_model = 'MG4010'
