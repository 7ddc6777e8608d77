"""DJI motors: M3508 (C620), M2006 (C610), GM6020 in voltage and in current mode.

The motors only hold their raw command; a :class:`rm_base.motors.dji.groups.DjiCommandGroup`
packs the shared frame (0x200, 0x1FF, 0x2FF, 0x1FE, 0x2FE). The rotor encoder is single
turn, so the joint position starts within half an output turn of zero and is unwrapped
from there.

Family options (``joints.<name>.<key>``): each class's ``options_schema``. ``si_per_raw``
may be ``1.62/16384`` for the other GM6020 current-mode scale (UNVERIFIED which is right;
3 A/16384 is the default). A GM6020 on voltage turns an effort into a voltage with
``V = R·I + Ke·ω``; R 1.8 Ω and Ke 60/(2π·13.33 rpm/V) = 0.716 V·s/rad are datasheet-level
values (not in docs/PROTOCOLS.md). ω there is the median rotor speed of the last three
frames, so that one corrupted frame cannot put the clamped voltage on a standing rotor.
"""

from __future__ import annotations

import collections
import math
from typing import ClassVar

import can
from mypy_extensions import mypyc_attr

from rm_base.config.schema import Schema, integer, number
from rm_base.geometry.encoder import EncoderUnwrapper
from rm_base.hardware.actuators.base import Actuator, Defaults, Feedback, JointCommand
from rm_base.hardware.config import JointConfig, SafetyConfig
from rm_base.hardware.errors import HardwareConfigError, ValueRangeError
from rm_base.motors.dji import protocol as dji

_RPM_TO_RAD_S = dji.RAD_PER_S_PER_RPM
#: Feedback faster than this times the type's no-load speed is implausible.
_PLAUSIBLE_SPEED_FACTOR = 2.0
_TAU = 2.0 * math.pi

#: Frames whose median rotor speed a GM6020 on voltage compensates (one outlier outvoted).
_BACK_EMF_FRAMES = 3
#: A gap between frames after which the speeds before it are not used [ns].
_BACK_EMF_GAP_NS = 10_000_000

#: GM6020 speed constant 13.33 rpm/V -> back-EMF constant [V·s/rad].
GM6020_BACK_EMF_V_S_PER_RAD = 60.0 / (_TAU * 13.33)
GM6020_RESISTANCE_OHM = 1.8

#: The scales of a DJI ESC's frames: the joint's options, and its simulated ESC's keys.
SCALE_KEYS = (
    integer('raw_limit', None, gt=0,
            description="command clamp [raw]; default the kind's (GM6020 voltage 25000, at "
            'most 30000)'),
    number('si_per_raw', None, gt=0.0,
           description="A (V for a GM6020 on voltage) per raw command unit; default the kind's"),
    number('feedback_amps_per_raw', None, gt=0.0,
           description="A per raw unit of the feedback current; default the kind's"),
)


@mypyc_attr(allow_interpreted_subclasses=True)
class DjiActuator(Actuator):
    """A DJI ESC-driven motor; the group packs its raw command."""

    kind: ClassVar[dji.DjiKind]
    options_schema = Schema(SCALE_KEYS)
    start_near_zero = True

    def __init__(self, config: JointConfig, safety: SafetyConfig | None = None) -> None:
        """Build the actuator; see the module docstring for the options.

        Raises:
            HardwareConfigError: invalid id or option.
        """
        super().__init__(config, safety)
        opts = self.options
        self.spec = dji.make_dji_spec(
            self.kind,
            raw_limit=opts['raw_limit'],
            si_per_raw=opts['si_per_raw'],
            feedback_amps_per_raw=opts['feedback_amps_per_raw'],
        )
        try:
            self.command_frame_id, self.slot = self.spec.command_slot(config.id)
        except ValueRangeError as err:
            raise HardwareConfigError(f'joints.{config.name}.id: {err}') from err
        self.feedback_id = self.spec.feedback_id(config.id)
        self._kt = self._current_kt()
        # rotor torque per ampere: the joint constant spread over the gear ratio
        self._kt_rotor = self._kt / self.gear_ratio
        self._unwrapper = EncoderUnwrapper(dji.ENCODER_TICKS_PER_REV)
        self._has_temperature = self.spec.has_temperature
        # A DJI frame has no checksum: a corrupted one (or another device on the id) can
        # carry any rotor speed, and a GM6020 in voltage mode turns a wrong speed into a
        # wrong back-EMF term, i.e. a torque far beyond its limit. Twice the motor's
        # no-load speed is more than it ever turns; beyond it the frame is rejected.
        self.max_rotor_rpm = round(
            _PLAUSIBLE_SPEED_FACTOR * self.defaults.max_velocity * self.defaults.gear_ratio
            / _RPM_TO_RAD_S
        )
        #: Raw command for the group, computed by update().
        self.command_raw = 0

    def _feedback_ids(self) -> tuple[int, ...]:
        return (self.feedback_id,)

    def _decode(self, msg: can.Message) -> tuple[float, float, float, float | None, int]:
        fb = dji.decode_feedback(msg.data, self._has_temperature)
        if abs(fb.rotor_rpm) > self.max_rotor_rpm:
            raise ValueRangeError(
                f'rotor speed {fb.rotor_rpm} rpm beyond twice the no-load speed '
                f'(+-{self.max_rotor_rpm} rpm): a corrupted frame'
            )
        angle = self._unwrapper.update(fb.angle_ticks)  # rotor, multi-turn, exact ticks
        torque = fb.current_raw * self.spec.feedback_amps_per_raw * self._kt_rotor
        return angle, fb.rotor_rpm * _RPM_TO_RAD_S, torque, fb.temperature_c, 0

    def _set_output(self, effort: float, command: JointCommand, feedback: Feedback) -> float:
        amps = self.direction * effort / self._kt
        raw = self.spec.raw_from_si(amps)
        self.command_raw = raw
        return self.direction * raw * self.spec.si_per_raw * self._kt

    def _set_zero_output(self) -> None:
        self.command_raw = 0

    def zero_here(self) -> float:
        """Make the present position the zero (an offset; the ESC knows no zero).

        Only at a direct drive (gear ratio 1, e.g. a GM6020): behind a gearbox the rotor's
        single-turn encoder cannot tell after a restart which output angle it is at.

        Raises:
            CommandRejectedError: geared, or no feedback yet.
        """
        return self._zero_at_direct_drive()


@mypyc_attr(allow_interpreted_subclasses=True)
class M3508(DjiActuator):
    """M3508 with a C620 ESC (±20 A, gear 3591/187, 0.3 N·m/A at the output)."""

    type_name = 'm3508'
    kind = dji.DjiKind.C620
    # 20 A * 0.3 N·m/A = 6 N·m; no-load about 482 rpm at the output = 50 rad/s
    defaults = Defaults(3591.0 / 187.0, 0.3, 6.0, 50.0, 80.0)


@mypyc_attr(allow_interpreted_subclasses=True)
class M2006(DjiActuator):
    """M2006 with a C610 ESC (±10 A, gear 36, 0.18 N·m/A; no temperature feedback)."""

    type_name = 'm2006'
    kind = dji.DjiKind.C610
    # 10 A * 0.18 N·m/A = 1.8 N·m; no-load about 500 rpm at the output = 52 rad/s
    defaults = Defaults(36.0, 0.18, 1.8, 52.0, 80.0)


@mypyc_attr(allow_interpreted_subclasses=True)
class Gm6020Current(DjiActuator):
    """GM6020 in current mode (0x1FE/0x2FE; enable the current loop in the DJI assistant)."""

    type_name = 'gm6020_current'
    kind = dji.DjiKind.GM6020_CURRENT
    # direct drive, 0.741 N·m/A; 1.2 N·m rated; no-load 320 rpm = 33.5 rad/s
    defaults = Defaults(1.0, 0.741, 1.2, 33.5, 80.0)


@mypyc_attr(allow_interpreted_subclasses=True)
class Gm6020Voltage(DjiActuator):
    """GM6020 in voltage mode (0x1FF/0x2FF): effort -> current -> ``V = R·I + Ke·ω``."""

    type_name = 'gm6020'
    kind = dji.DjiKind.GM6020_VOLTAGE
    defaults = Defaults(1.0, 0.741, 1.2, 33.5, 80.0)
    options_schema = Schema((
        *SCALE_KEYS,
        number('resistance', GM6020_RESISTANCE_OHM, unit='Ohm', gt=0.0,
               description='winding resistance in V = R·I + Ke·w (datasheet level)'),
        number('back_emf_constant', GM6020_BACK_EMF_V_S_PER_RAD, unit='V·s/rad', gt=0.0,
               description='Ke in V = R·I + Ke·w (datasheet level)'),
    ))

    def __init__(self, config: JointConfig, safety: SafetyConfig | None = None) -> None:
        """Build the actuator; see the module docstring for the options.

        Raises:
            HardwareConfigError: invalid id or option.
        """
        super().__init__(config, safety)
        self.resistance: float = self.options['resistance']
        self.back_emf_constant: float = self.options['back_emf_constant']
        # The rotor speeds of the last frames, for the back-EMF term (see back_emf_speed).
        self._speeds: collections.deque[float] = collections.deque(maxlen=_BACK_EMF_FRAMES)
        self._last_frame_ns: int | None = None

    def handle_frame(self, msg: can.Message, now_ns: int) -> bool:
        """As for every actuator; also keeps the rotor speed for the back-EMF term."""
        before = self._feedback
        claimed = super().handle_frame(msg, now_ns)
        feedback = self._feedback
        if feedback is not None and feedback is not before:  # a frame was taken
            last, self._last_frame_ns = self._last_frame_ns, now_ns
            if last is None or now_ns - last > _BACK_EMF_GAP_NS:
                self._speeds.clear()  # after a gap the old speeds tell nothing
            self._speeds.append(feedback.device_velocity)
        return claimed

    @property
    def back_emf_speed(self) -> float:
        """The rotor speed [rad/s] the voltage compensates: the median of the last frames.

        A DJI frame has no checksum, and a corrupted one inside the speed bound still reads
        as a speed; put into ``Ke·ω`` once, it would drive the clamped voltage into a
        rotor that is not turning. The median of three frames never takes a lone outlier
        and follows a real change one frame late. Of two frames (after start or a gap)
        the slower is taken, of one that one.
        """
        speeds = sorted(self._speeds)
        if len(speeds) == 2:
            return min(speeds, key=abs)
        return speeds[len(speeds) // 2] if speeds else 0.0

    def _set_output(self, effort: float, command: JointCommand, feedback: Feedback) -> float:
        rotor_velocity = self.back_emf_speed
        amps = self.direction * effort / self._kt
        volts = self.resistance * amps + self.back_emf_constant * rotor_velocity
        raw = self.spec.raw_from_si(volts)
        self.command_raw = raw
        applied_amps = (raw * self.spec.si_per_raw - self.back_emf_constant * rotor_velocity) / (
            self.resistance
        )
        return self.direction * applied_amps * self._kt
