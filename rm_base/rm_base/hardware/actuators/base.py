"""The shared actuator base: commands, control modes, safety and SI conversion.

Why one module: the one class every family shares and the records it speaks in; its length
is the checks and log lines, which keep each family's hooks short.

:class:`Actuator` owns every public method, check and log line. A motor family overrides
only protected hooks:

* ``_feedback_ids()`` — arbitration ids whose frames may be for this actuator;
* ``_match(msg)`` — whether a frame with one of those ids is really this one's;
* ``_decode(msg)`` — device values at the motor's measuring shaft
  (angle [rad], velocity [rad/s], torque [N·m], temperature [°C] or None, error code);
* ``_set_output(effort, command)`` / ``_set_zero_output()`` — turn the joint effort
  computed by :meth:`Actuator.update` into device units (for example a DJI raw current);
* ``_pack()`` — the actuator's own CAN frame, or None if a command group packs it.

Conversion at the edge: the base turns decoded values into joint (output-shaft) SI values
the moment a frame arrives::

    position = direction * (angle / gear_ratio - zero_offset) [+ whole turns, see below]
    velocity = direction * velocity / gear_ratio
    effort   = direction * torque * gear_ratio

Safety, independent of any plugin: every output is clamped to ``max_effort``; a joint
without feedback for ``feedback_timeout_s`` is offline; over-temperature, a device fault,
implausible feedback, no command for ``command_timeout_s``, a failed bus (from the failure
until it is back, at least one tick after that, and until a command newer than the
recovery) and shutdown all hold the output at zero (``MODE_OFF`` applied). A NaN/inf
command is rejected, counted, and the previous (safe) target stays in force.

Faults latch (docs/RELIABILITY.md, "Faults latch and clear on evidence"): over-temperature,
a device fault, implausible feedback and going offline after having been online clear only
once their condition has been gone for ``safety.fault_clear_s`` on consistent frames. A
frame is implausible when its temperature moved more than ``max_temperature_step_c`` since
the previous frame, or its angle jumped more than an eighth of a turn while both frames say
the shaft was (nearly) still; such a frame is counted and never becomes the joint's feedback.
"""

from __future__ import annotations

import abc
import enum
import logging
import math
import time
from typing import Any, ClassVar, NamedTuple

import can
from mypy_extensions import mypyc_attr

from rm_base.config.schema import Schema, unknown_keys_message
from rm_base.control import Pid, PidGains, build_pid
from rm_base.hardware.config import JOINT_SCHEMA, JointConfig, SafetyConfig
from rm_base.hardware.errors import CommandRejectedError, HardwareConfigError, ProtocolError
from rm_base.joints import InvalidTargetError, JointState, JointTarget, Mode, check_target

_log = logging.getLogger(__name__)
_TAU = 2.0 * math.pi


class HoldReason(enum.Enum):
    """Why a joint's output is held at zero (``NONE``: it is not)."""

    NONE = 'none'
    OFF = 'off'  # commanded MODE_OFF
    NO_COMMAND = 'no_command'  # never commanded
    COMMAND_TIMEOUT = 'command_timeout'
    OFFLINE = 'offline'  # no feedback within feedback_timeout_s
    OVER_TEMPERATURE = 'over_temperature'
    DEVICE_FAULT = 'device_fault'  # the device reports an error code
    IMPLAUSIBLE = 'implausible_feedback'  # a frame no motor could send after the last one
    BUS_RECOVERY = 'bus_recovery'  # the bus came back; waiting for a fresh command
    ERROR = 'error'  # an internal exception in this joint's update
    SHUTDOWN = 'shutdown'


#: Holds that are normal operation, logged at INFO (the others at WARNING).
_QUIET_HOLDS = frozenset({HoldReason.OFF, HoldReason.NO_COMMAND, HoldReason.SHUTDOWN})


class JointCommand(NamedTuple):
    """A validated joint command, stamped when it was accepted.

    Attributes:
        mode: :class:`Mode`.
        position: [rad].
        velocity: [rad/s].
        effort: [N·m].
        kp: [N·m/rad].
        kd: [N·m·s/rad].
        stamp_ns: when the command was issued, on the clock [ns] (its stamp, or its
            acceptance for a command without one); its timeout runs from here.
    """

    mode: Mode
    position: float
    velocity: float
    effort: float
    kp: float
    kd: float
    stamp_ns: int


class Feedback(NamedTuple):
    """Latest decoded feedback at the joint (written whole by the receive thread).

    Attributes:
        stamp_ns: receive time [ns].
        position: [rad], continuous.
        velocity: [rad/s].
        effort: [N·m].
        temperature: [°C], or None if the device reports none.
        error_code: device fault code, 0 = none.
        device_velocity: velocity of the measuring shaft (DJI: rotor) [rad/s], for models
            that need it (GM6020 back-EMF).
    """

    stamp_ns: int
    position: float
    velocity: float
    effort: float
    temperature: float | None
    error_code: int
    device_velocity: float


class Defaults(NamedTuple):
    """Per-type defaults for the optional joint keys.

    Attributes:
        gear_ratio: motor turns per joint turn.
        torque_constant: [N·m/A] at the joint with this gear ratio (None: not current-driven).
        max_effort: [N·m].
        max_velocity: [rad/s].
        temperature_limit: [°C].
    """

    gear_ratio: float
    torque_constant: float | None
    max_effort: float
    max_velocity: float
    temperature_limit: float


class Unwrapper:
    """Counts whole wraps of a float reading that wraps over ``span`` (no drift).

    ``rm_base.geometry.encoder.EncoderUnwrapper`` does this for integer encoder ticks (DJI);
    this one is for float readings such as a Damiao position wrapping over 2·PMAX.
    """

    __slots__ = ('_half', '_last', '_span', '_turns')

    def __init__(self, span: float) -> None:
        self._span = span
        self._half = span / 2.0
        self._last: float | None = None
        self._turns = 0

    def update(self, reading: float) -> float:
        """Return the continuous value for a new reading."""
        last = self._last
        if last is not None:
            delta = reading - last
            if delta > self._half:
                self._turns -= 1
            elif delta < -self._half:
                self._turns += 1
        self._last = reading
        return reading + self._turns * self._span

    @property
    def turns(self) -> int:
        """Whole spans added so far (negative when unwrapped downwards)."""
        return self._turns


#: At most one line a second about a joint's link going and coming [ns].
_LINK_LOG_PERIOD_NS = 1_000_000_000
#: A shaft both frames say turns slower than this [rad/s] is still for the angle check.
_STILL_RAD_S = 5.0
#: Largest angle step [rad] of a still shaft between two frames (it moves 0.25 rad at most
#: in the longest gap judged).
_STILL_STEP_RAD = math.pi / 4.0
#: Frames further apart than this [ns] are not compared for an angle step.
_STEP_WINDOW_NS = 50_000_000


def _clamp(x: float, limit: float) -> float:
    return limit if x > limit else -limit if x < -limit else x


# Compiled (rm_base/runtime/compiled.py); other motor families and tests subclass it. Not an
# abc.ABC: compiled, its subclasses would share one isinstance cache (docs/ARCHITECTURE.md,
# "The compiled loop"); mypy still refuses an instance of a class with abstract methods.
@mypyc_attr(allow_interpreted_subclasses=True)
class Actuator:
    """Base of every motor family; see the module docstring for the hooks.

    Thread model: :meth:`handle_frame` runs on the bus receive thread and replaces the
    feedback snapshot in one assignment; :meth:`set_command` (any thread) replaces the
    command in one assignment; :meth:`update` and :meth:`pack_command` run on the
    scheduler thread only.
    """

    #: Type name in the config (``m3508``...), set by each concrete class.
    type_name: ClassVar[str] = ''
    #: Defaults of the optional joint keys (a family may set it per instance before
    #: calling ``Actuator.__init__``, e.g. from a motor model).
    defaults: Defaults
    #: Family-specific config keys (``JointConfig.options``), declared once.
    options_schema: ClassVar[Schema] = Schema(())
    #: Start the multi-turn position within half a turn of zero (single-turn encoders).
    start_near_zero: ClassVar[bool] = False
    #: Id of this actuator's own command frame (families that pack one set it).
    command_id: int

    @classmethod
    def read_options(cls, config: JointConfig) -> dict[str, Any]:
        """The joint's options through ``options_schema`` (a subclass may need them early).

        Raises:
            HardwareConfigError: an unknown, missing or invalid option, named by its key.
        """
        where = f'joints.{config.name}'
        unknown = set(config.options) - cls.options_schema.names
        if unknown:  # a typo of a common key lands here: name every key a joint may have
            raise HardwareConfigError(unknown_keys_message(
                where, unknown, JOINT_SCHEMA.names | cls.options_schema.names))
        return cls.options_schema.read(where, config.options, HardwareConfigError)

    def __init__(self, config: JointConfig, safety: SafetyConfig | None = None) -> None:
        """Build the actuator from its config.

        Args:
            config: the joint.
            safety: safety rules (defaults if None).

        Raises:
            HardwareConfigError: unknown option or invalid value.
        """
        safety = safety or SafetyConfig()
        #: The joint's options, typed, defaults filled in (``options_schema``).
        self.options = self.read_options(config)
        d = self.defaults
        self.config = config
        self.name = config.name
        self.bus_name = config.bus
        self.direction = config.direction
        self.gear_ratio = config.gear_ratio if config.gear_ratio is not None else d.gear_ratio
        # The type defaults are at the stock gearbox: behind another gear ratio the same
        # motor gives torque x (ratio / stock) and speed x (stock / ratio) at the joint
        # (e.g. an M3508 friction wheel without its 19.2:1 gearbox spins 19.2x faster).
        torque_scale = self.gear_ratio / d.gear_ratio
        self.torque_constant: float | None
        if config.torque_constant is not None:
            self.torque_constant = config.torque_constant
        elif d.torque_constant is not None:
            self.torque_constant = d.torque_constant * torque_scale
        else:
            self.torque_constant = None
        self.max_effort = (
            config.max_effort if config.max_effort is not None else d.max_effort * torque_scale
        )
        self.max_velocity = (
            config.max_velocity
            if config.max_velocity is not None
            else d.max_velocity / torque_scale
        )
        self.temperature_limit = (
            config.temperature_limit
            if config.temperature_limit is not None
            else d.temperature_limit
        )
        self.zero_offset = config.zero_offset
        self._feedback_timeout_ns = int(safety.feedback_timeout_s * 1e9)
        self._command_timeout_ns = int(safety.command_timeout_s * 1e9)
        self._temperature_resume = self.temperature_limit - safety.temperature_hysteresis_c
        self._fault_clear_ns = int(safety.fault_clear_s * 1e9)
        self._max_temperature_step = safety.max_temperature_step_c
        self._velocity_pid = build_pid(config.velocity_pid)
        self._position_pid = build_pid(config.position_pid)
        # shared state (single assignment each)
        self._feedback: Feedback | None = None
        self._command: JointCommand | None = None
        self._bus_down = False
        self._recovered_ns: int | None = None
        self._zero_since_recovery = False
        self._shutdown = False
        # a new (zero_offset, turn shift) for the next frame (set_zero; one assignment)
        self._pending_zero: tuple[float, float] | None = None
        # scheduler-thread state
        self._turn_shift = 0.0
        self._hold = HoldReason.NO_COMMAND
        self._applied_mode = Mode.OFF
        self._last_mode = Mode.OFF
        self._effort_out = 0.0
        self._online = False
        self._overheated = False
        # latches (scheduler thread): since when each condition has been gone [ns]
        self._cool_since: int | None = None
        self._fault_latched = False
        self._fault_gone_since: int | None = None
        self._ever_online = False
        self._back_since: int | None = None  # online again after having been offline
        # the thread that decodes (one per joint): the previous frame's values, plausible
        # or not; fields, not a tuple, so a frame allocates nothing for them
        self._raw_ns: int | None = None
        self._raw_angle = 0.0
        self._raw_velocity = 0.0
        self._raw_temperature: float | None = None
        self._implausible_ns: int | None = None  # the newest implausible frame (one assignment)
        # counters
        self.frames_decoded = 0
        self.decode_errors = 0
        self.commands_accepted = 0
        self.commands_rejected = 0
        self.update_errors = 0
        self.implausible_frames = 0
        self.last_rejection: str | None = None
        # the link's lines (online, offline and their holds): at most one a period
        self._link_quiet_until_ns = 0
        self._link_unsaid = 0

    # --- hooks ---
    @abc.abstractmethod
    def _feedback_ids(self) -> tuple[int, ...]:
        """Arbitration ids whose frames may be this actuator's."""
        raise NotImplementedError(f'{type(self).__name__}._feedback_ids')

    def _match(self, msg: can.Message) -> bool:
        return True

    @abc.abstractmethod
    def _decode(self, msg: can.Message) -> tuple[float, float, float, float | None, int]:
        """Angle [rad], velocity [rad/s], torque [N·m], temperature [°C] or None, error code."""
        raise NotImplementedError(f'{type(self).__name__}._decode')

    @abc.abstractmethod
    def _set_output(self, effort: float, command: JointCommand, feedback: Feedback) -> float:
        """Compute the device command for ``effort`` [N·m]; return the effort really applied."""
        raise NotImplementedError(f'{type(self).__name__}._set_output')

    @abc.abstractmethod
    def _set_zero_output(self) -> None:
        """Set the device command for no output."""
        raise NotImplementedError(f'{type(self).__name__}._set_zero_output')

    def _pack(self) -> can.Message | None:
        return None

    def _is_fault(self, error_code: int) -> bool:
        return error_code != 0

    def _after_update(self, now_ns: int) -> None:
        """Called at the end of every update (e.g. to schedule an enable frame)."""

    # --- feedback (receive thread) ---
    def feedback_ids(self) -> tuple[int, ...]:
        """Arbitration ids to route to :meth:`handle_frame`."""
        return self._feedback_ids()

    def reply_key(self) -> str | None:
        """What sets this joint's replies apart where several share a frame id, in words.

        Two joints of one bus with the same key could not be told apart (the hardware
        refuses such a config). None: the joint's feedback id is its own.
        """
        return None

    def handle_frame(self, msg: can.Message, now_ns: int) -> bool:
        """Decode a frame if it is this actuator's and store the joint-side SI values.

        Args:
            msg: received frame.
            now_ns: receive time on the scheduler's clock [ns].

        Returns:
            True if the frame was for this actuator (even if it was malformed).
        """
        if not self._match(msg):
            return False
        try:
            angle, velocity, torque, temperature, error_code = self._decode(msg)
        except ProtocolError as err:
            self.decode_errors += 1
            if self.decode_errors == 1 or self.decode_errors % 1000 == 0:
                _log.warning(
                    '%s: bad frame 0x%X %s (%d so far): %s',
                    self.name,
                    msg.arbitration_id,
                    bytes(msg.data).hex(' '),
                    self.decode_errors,
                    err,
                )
            return True
        if not self._plausible(now_ns, angle, velocity, temperature):
            return True
        pending = self._pending_zero
        if pending is not None:
            self._pending_zero = None
            self.zero_offset, self._turn_shift = pending
        d = self.direction
        g = self.gear_ratio
        position = d * (angle / g - self.zero_offset)
        if self._feedback is None and self.start_near_zero:
            self._turn_shift = -_TAU * round(position / _TAU)
        self._feedback = Feedback(
            now_ns,
            position + self._turn_shift,
            d * velocity / g,
            d * torque * g,
            temperature,
            error_code,
            velocity,
        )
        self.frames_decoded += 1
        return True

    def _plausible(
        self, now_ns: int, angle: float, velocity: float, temperature: float | None
    ) -> bool:
        """Whether a frame could follow the previous one; count and latch one that cannot."""
        last_ns, last_angle = self._raw_ns, self._raw_angle
        last_velocity, last_temperature = self._raw_velocity, self._raw_temperature
        self._raw_ns, self._raw_angle = now_ns, angle
        self._raw_velocity, self._raw_temperature = velocity, temperature
        if last_ns is None:
            return True
        reason = ''
        if (temperature is not None and last_temperature is not None
                and abs(temperature - last_temperature) > self._max_temperature_step):
            reason = f'temperature {last_temperature:g} -> {temperature:g} degC'
        elif (now_ns - last_ns <= _STEP_WINDOW_NS and abs(velocity) < _STILL_RAD_S
                and abs(last_velocity) < _STILL_RAD_S
                and abs(angle - last_angle) > _STILL_STEP_RAD):
            reason = f'angle step {angle - last_angle:+.3f} rad while still'
        if not reason:
            return True
        self.implausible_frames += 1
        self._implausible_ns = now_ns
        if self.implausible_frames == 1 or self.implausible_frames % 100 == 0:
            _log.warning('%s: implausible feedback (%d so far): %s; output held %g s',
                         self.name, self.implausible_frames, reason,
                         self._fault_clear_ns / 1e9)
        return False

    # --- commands (any thread) ---
    def set_command(
        self,
        mode: object,
        now_ns: int,
        *,
        position: object = 0.0,
        velocity: object = 0.0,
        effort: object = 0.0,
        kp: object = 0.0,
        kd: object = 0.0,
    ) -> None:
        """Accept a joint target (output shaft, SI), or reject it.

        The fields are checked here (``check_target``), whatever their type: typed as
        floats, the compiled class would refuse a wrong one with a bare TypeError.

        Args:
            mode: :class:`Mode` value (rm_msgs/ActuatorCmd.MODE_*).
            now_ns: clock time [ns], for the command timeout.
            position: [rad] (POSITION, MIT).
            velocity: [rad/s] (VELOCITY; feed-forward in POSITION; MIT).
            effort: [N·m] (EFFORT; feed-forward in MIT).
            kp: [N·m/rad] >= 0, MIT only.
            kd: [N·m·s/rad] >= 0, MIT only.

        Raises:
            CommandRejectedError: unknown mode, a NaN/inf field or negative gains. The
                previous target stays in force (and times out as usual); the rejection is
                counted and logged.
        """
        try:
            target = check_target(
                mode, position=position, velocity=velocity, effort=effort, kp=kp, kd=kd
            )
        except InvalidTargetError as err:
            raise self._rejection(str(err)) from None
        self.set_target(target, now_ns)

    def set_target(self, target: JointTarget, now_ns: int) -> None:
        """Accept a target validated where it entered (``rm_base.joints.check_target``).

        Args:
            target: the joint's target.
            now_ns: clock time [ns], for the command timeout.
        """
        self._command = JointCommand(
            target.mode, target.position, target.velocity, target.effort, target.kp,
            target.kd, now_ns,
        )
        self.commands_accepted += 1

    def zero_here(self) -> float:
        """Make the present position the joint's zero, from its next feedback frame on.

        Returns:
            The new ``zero_offset`` [rad] (what a calibration file keeps for a restart).

        Raises:
            CommandRejectedError: the family cannot (here: no angle at the output that a
                restart would find again), or there is no feedback yet.
        """
        raise CommandRejectedError(
            f'{self.name}: a {self.type_name} has no absolute angle at its output to zero'
        )

    def _zero_at_direct_drive(self) -> float:
        """The zero as an offset, for a rotor encoder only where it turns with the output.

        Behind a gearbox the rotor's single-turn encoder cannot tell after a restart which
        output angle it is at, so such a zero would not hold.

        Raises:
            CommandRejectedError: geared, or no feedback yet.
        """
        if self.gear_ratio != 1.0:
            raise CommandRejectedError(
                f'{self.name}: its encoder turns {self.gear_ratio:g} times per output turn, '
                'so a zero would not hold across a restart'
            )
        return self._zero_by_offset()

    def _zero_by_offset(self) -> float:
        # For an absolute single-turn encoder at the output: the zero is where it reads now,
        # as an angle in [0, 2pi), and the whole turns go so that the position reads 0.
        fb = self._feedback
        if fb is None:
            raise CommandRejectedError(f'{self.name}: no feedback yet')
        d = self.direction
        output_angle = (fb.position - self._turn_shift) / d + self.zero_offset
        zero = output_angle % _TAU
        self._pending_zero = (zero, -_TAU * round(d * (output_angle - zero) / _TAU))
        return zero

    def _rejection(self, reason: str) -> CommandRejectedError:
        """Count and log a rejected command; return the error to raise."""
        self.commands_rejected += 1
        self.last_rejection = reason
        if self.commands_rejected == 1 or self.commands_rejected % 100 == 0:
            _log.warning(
                '%s: command rejected (%d so far): %s', self.name, self.commands_rejected, reason
            )
        return CommandRejectedError(f'{self.name}: command rejected: {reason}')

    def notify_bus_down(self, now_ns: int) -> None:
        """The bus failed at ``now_ns``: hold zero output until it is back and re-commanded."""
        self._bus_down = True

    def notify_bus_recovered(self, now_ns: int) -> None:
        """The bus is back: output zero at least one tick, then until a newer command."""
        self._zero_since_recovery = False
        self._recovered_ns = now_ns  # set before clearing _bus_down: never both unset
        self._bus_down = False

    def shutdown(self) -> None:
        """Hold zero output from now on (the final frames are still packed and sent)."""
        self._shutdown = True

    # --- control (scheduler thread) ---
    def update(self, now_ns: int, dt: float) -> None:
        """Run safety checks and the control law for one tick; never raises.

        Args:
            now_ns: tick time [ns].
            dt: time since the previous tick [s], > 0.
        """
        try:
            self._update(now_ns, dt)
            self._after_update(now_ns)
        except Exception:
            self.update_errors += 1
            if self.update_errors == 1 or self.update_errors % 1000 == 0:
                _log.exception(
                    '%s: update failed (%d so far); output zero', self.name, self.update_errors
                )
            self._hold_zero(HoldReason.ERROR)

    def _current_kt(self) -> float:
        """Kt [N·m/A] of a joint whose family speaks in amperes (its Defaults give one)."""
        if self.torque_constant is None:
            raise HardwareConfigError(
                f'joints.{self.name}.torque_constant is required for type {self.type_name!r}'
            )
        return self.torque_constant

    @property
    def effort_out(self) -> float:
        """The effort this tick's update commands [N·m] (0 while held at zero)."""
        return self._effort_out

    @property
    def loop_gains(self) -> tuple[PidGains | None, PidGains | None]:
        """The velocity and position loops' gains now; None for a loop that is not positional."""
        velocity, position = self._velocity_pid, self._position_pid
        return (velocity.gains if isinstance(velocity, Pid) else None,
                position.gains if isinstance(position, Pid) else None)

    def set_loop_gains(
        self, velocity: PidGains | None = None, position: PidGains | None = None
    ) -> None:
        """New gains for the positional velocity and position loops; their state stays.

        For live tuning, between two updates (the loop's thread). None keeps a loop as it is.

        Raises:
            TypeError: the loop is not a positional PID (its form is read at start-up).
        """
        for loop, pid, gains in (('velocity', self._velocity_pid, velocity),
                                 ('position', self._position_pid, position)):
            if gains is None:
                continue
            if not isinstance(pid, Pid):
                raise TypeError(f'{self.name}: the {loop} loop is not a positional PID')
            pid.gains = gains

    def scale_output(self, factor: float) -> None:
        """Scale this tick's output by factor in [0, 1] (a group stage after the update).

        Nothing changes while the output is held at zero; the control loops keep their
        own state (their integrals see the effort they asked for).

        Raises:
            ValueError: factor outside [0, 1] or NaN.
        """
        if not 0.0 <= factor <= 1.0:
            raise ValueError(f'{self.name}: output scale must be in [0, 1], got {factor!r}')
        cmd, fb = self._command, self._feedback
        if self._applied_mode is Mode.OFF or factor == 1.0 or cmd is None or fb is None:
            return
        self._effort_out = self._set_output(self._effort_out * factor, cmd, fb)

    def _hold_reason(
        self, now_ns: int, fb: Feedback | None, cmd: JointCommand | None
    ) -> HoldReason:
        if self._shutdown:
            return HoldReason.SHUTDOWN
        online = fb is not None and now_ns - fb.stamp_ns <= self._feedback_timeout_ns
        if online != self._online:
            self._online = online
            if online:
                self._say_link(logging.INFO, f'{self.name}: online')
                # the first time is a start, not a fault: only a return must prove itself
                self._back_since = now_ns if self._ever_online else None
                self._ever_online = True
            else:
                self._say_link(logging.WARNING, f'{self.name}: offline (no feedback for '
                               f'{self._feedback_timeout_ns / 1e6:.0f} ms)')
        if fb is None or not online:
            return HoldReason.OFFLINE
        clear_ns = self._fault_clear_ns
        temperature = fb.temperature
        if temperature is not None:
            if temperature >= self.temperature_limit:
                self._overheated = True
                self._cool_since = None
            elif temperature < self._temperature_resume:
                if self._cool_since is None:
                    self._cool_since = now_ns
                if self._overheated and now_ns - self._cool_since >= clear_ns:
                    self._overheated = False
                    _log.info('%s: over-temperature cleared (%.0f degC for %g s)',
                              self.name, temperature, clear_ns / 1e9)
            else:
                self._cool_since = None
        faulted = self._is_fault(fb.error_code)
        if faulted:
            self._fault_latched = True
            self._fault_gone_since = None
        elif self._fault_latched:
            if self._fault_gone_since is None:
                self._fault_gone_since = now_ns
            if now_ns - self._fault_gone_since >= clear_ns:
                self._fault_latched = False
        if faulted:  # what the device says now is the reason shown
            return HoldReason.DEVICE_FAULT
        if self._overheated:
            return HoldReason.OVER_TEMPERATURE
        if self._fault_latched:
            return HoldReason.DEVICE_FAULT
        implausible = self._implausible_ns
        if implausible is not None and now_ns - implausible < clear_ns:
            return HoldReason.IMPLAUSIBLE
        back = self._back_since
        if back is not None:
            if now_ns - back < clear_ns:
                return HoldReason.OFFLINE
            self._back_since = None
        if self._bus_down:
            return HoldReason.BUS_RECOVERY
        recovered = self._recovered_ns
        if recovered is not None:
            if not self._zero_since_recovery or cmd is None or cmd.stamp_ns <= recovered:
                self._zero_since_recovery = True
                return HoldReason.BUS_RECOVERY
            self._recovered_ns = None
        if cmd is None:
            return HoldReason.NO_COMMAND
        if now_ns - cmd.stamp_ns > self._command_timeout_ns:
            return HoldReason.COMMAND_TIMEOUT
        if cmd.mode is Mode.OFF:
            return HoldReason.OFF
        return HoldReason.NONE

    def _update(self, now_ns: int, dt: float) -> None:
        fb = self._feedback
        cmd = self._command
        hold = self._hold_reason(now_ns, fb, cmd)
        if hold is not HoldReason.NONE:
            self._hold_zero(hold)
            return
        assert fb is not None and cmd is not None  # no hold: both are there
        mode = cmd.mode
        if mode is not self._last_mode:
            self._velocity_pid.reset()
            self._position_pid.reset()
            self._last_mode = mode
        if self._hold is not HoldReason.NONE:
            text = f'{self.name}: output resumed in {mode.name} (was held: {self._hold.value})'
            if self._hold is HoldReason.OFFLINE:
                self._say_link(logging.INFO, text)
            else:
                _log.info(text)
            self._hold = HoldReason.NONE
        if mode is Mode.EFFORT:
            effort = cmd.effort
        elif mode is Mode.VELOCITY:
            target = _clamp(cmd.velocity, self.max_velocity)
            effort = self._velocity_pid.update(target, fb.velocity, dt)
        elif mode is Mode.POSITION:
            target = self._position_pid.update(cmd.position, fb.position, dt) + cmd.velocity
            target = _clamp(target, self.max_velocity)
            effort = self._velocity_pid.update(target, fb.velocity, dt)
        else:  # MIT
            effort = (
                cmd.kp * (cmd.position - fb.position)
                + cmd.kd * (cmd.velocity - fb.velocity)
                + cmd.effort
            )
        effort = _clamp(effort, self.max_effort)
        self._effort_out = self._set_output(effort, cmd, fb)
        self._applied_mode = mode

    def _hold_zero(self, reason: HoldReason) -> None:
        if reason is not self._hold:
            level = logging.INFO if reason in _QUIET_HOLDS else logging.WARNING
            text = f'{self.name}: output held at zero ({reason.value})'
            if reason is HoldReason.OFFLINE:
                self._say_link(level, text)
            else:
                _log.log(level, text)
            self._hold = reason
            self._velocity_pid.reset()
            self._position_pid.reset()
            self._last_mode = Mode.OFF
        self._set_zero_output()
        self._effort_out = 0.0
        self._applied_mode = Mode.OFF

    def _say_link(self, level: int, text: str) -> None:
        # A joint whose link flaps (a loose connector) says so once a second with a count,
        # not a line per change: the lines of the other joints stay readable.
        now = time.monotonic_ns()
        if now < self._link_quiet_until_ns:
            self._link_unsaid += 1
            return
        if self._link_unsaid:
            text += f' ({self._link_unsaid} more link changes since the last line)'
        self._link_unsaid = 0
        self._link_quiet_until_ns = now + _LINK_LOG_PERIOD_NS
        _log.log(level, text)

    def pack_command(self) -> can.Message | None:
        """This actuator's frame for this tick, or None if a command group packs it."""
        return self._pack()

    def final_frames(self) -> list[can.Message]:
        """Frames to send at shutdown after the final zero command (e.g. DISABLE)."""
        return []

    # --- state ---
    @property
    def hold_reason(self) -> HoldReason:
        """Why the output is held at zero after the last update (NONE if it is not)."""
        return self._hold

    @property
    def feedback(self) -> Feedback | None:
        """Latest feedback snapshot, or None before the first frame."""
        return self._feedback

    @property
    def command(self) -> JointCommand | None:
        """Latest accepted command, or None."""
        return self._command

    def state(self, stamp_ns: int | None = None) -> JointState:
        """The joint state as of the last update (ActuatorState fields).

        stamp_ns: the state's stamp [ns]; default the receive time of its feedback.
        """
        fb = self._feedback
        if fb is None:
            return JointState(
                self.name,
                0.0,
                0.0,
                0.0,
                math.nan,
                False,
                0,
                int(self._applied_mode),
                self._effort_out,
                0 if stamp_ns is None else stamp_ns,
            )
        return JointState(
            self.name,
            fb.position,
            fb.velocity,
            fb.effort,
            math.nan if fb.temperature is None else float(fb.temperature),
            self._online,
            fb.error_code,
            int(self._applied_mode),
            self._effort_out,
            fb.stamp_ns if stamp_ns is None else stamp_ns,
        )

    def diagnostics(self) -> dict[str, Any]:
        """Counters and status for /diagnostics."""
        return {
            'type': self.type_name,
            'bus': self.bus_name,
            'hold_reason': self._hold.value,
            'frames_decoded': self.frames_decoded,
            'decode_errors': self.decode_errors,
            'commands_accepted': self.commands_accepted,
            'commands_rejected': self.commands_rejected,
            'last_rejection': self.last_rejection,
            'update_errors': self.update_errors,
            'implausible_frames': self.implausible_frames,
            'details': self.details(),
        }

    def details(self) -> dict[str, str | float]:
        """What this joint's family adds to its /diagnostics (a setting a user must see)."""
        return {}
