"""Simulated motor drivers on a CAN bus: DJI ESCs, Damiao motors, MIT Cheetah motors.

Each device owns a :class:`~rm_base.sim.motor.MotorModel` and behaves on the bus like the
real driver, using the device side of :mod:`rm_base.hardware.protocols` for every byte:

* DJI (C620 + M3508, C610 + M2006, GM6020): takes its slot of a group command frame
  (0x200/0x1FF/0x2FF/0x1FE/0x2FE), sends a feedback frame at a fixed rate (default 1 kHz)
  whether commanded or not, and drops to zero current when no command came for
  ``command_timeout`` (default 100 ms; the real C620's value is not documented).
* Damiao (DM4310, DM8009): answers each command frame with one feedback frame, but only
  while enabled; system frames (enable, disable, set zero, clear error) are always
  answered. MIT law computed on the motor; POS_VEL and VEL modes with internal loops.
  Over-temperature and (optional) command timeout latch an error code until cleared.
* MIT Cheetah (Ben Katz firmware): like Damiao but with its own reply (6 or 7 bytes to
  the master id, no error nibble, no temperature) and no clear-error frame.

Frames a device cannot use (wrong length, remote/extended/FD frames, a control frame for
another mode, undecodable values) are ignored and counted in :attr:`SimDevice.stats`.

The public methods are on :class:`SimDevice` (``receive``, ``control``, ``step``, ``emit``,
``inject``/``clear_faults``); each family implements the protected hooks.
"""

from __future__ import annotations

import math
import random
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from rm_base.hardware.errors import HardwareConfigError, ProtocolError, ValueRangeError
from rm_base.hardware.protocols import cheetah, damiao, dji, mit
from rm_base.sim._schedule import RateSchedule
from rm_base.sim.errors import SimConfigError
from rm_base.sim.faults import Fault, FaultKind
from rm_base.sim.motor import DriveMode, MotorModel, MotorParams, MotorType, motor_params

#: A frame a device sends: (11-bit arbitration id, data bytes).
Frame = tuple[int, bytes]

_NS_PER_S = 1_000_000_000
_STD_ID_MAX = 0x7FF


@dataclass
class DeviceStats:
    """Frame counters of one device (monotonic).

    Attributes:
        rx_frames: frames addressed to the device and used.
        ignored_frames: frames addressed to the device but unusable (malformed, wrong
            mode, remote/extended/FD, or a control frame while the motor cannot act on it).
        tx_frames: feedback and reply frames sent.
        garbage_frames: random frames sent by a GARBAGE fault.
        timeouts: times the command timeout cut the output.
    """

    rx_frames: int = 0
    ignored_frames: int = 0
    tx_frames: int = 0
    garbage_frames: int = 0
    timeouts: int = 0


class SimDevice(ABC):
    """One simulated motor with its driver, as seen on the CAN bus.

    Attributes:
        name: unique name in the world (``'wheel_fl'``).
        motor_type: the motor model.
        motor_id: the id set on the device (ESC id / CAN id).
        model: the physics.
        stats: frame counters.
        overtemp_c: winding temperature above which the driver cuts the output [°C], or
            None for no cut-out.
    """

    family: ClassVar[str]

    def __init__(
        self,
        name: str,
        motor_type: MotorType,
        motor_id: int,
        model: MotorModel,
        *,
        seed: int = 0,
        overtemp_c: float | None = None,
    ):
        self.name = name
        self.motor_type = motor_type
        self.motor_id = motor_id
        self.model = model
        self.stats = DeviceStats()
        self.overtemp_c = overtemp_c
        #: The config dict the device was built from, if any.
        self.config: dict[str, Any] | None = None
        self._faults: dict[FaultKind, Fault] = {}
        self._garbage: RateSchedule | None = None
        self._rng = random.Random(seed)

    # -- routing -------------------------------------------------------------------------

    @property
    @abstractmethod
    def listen_ids(self) -> frozenset[int]:
        """Standard ids of the frames this device reads."""

    @property
    @abstractmethod
    def transmit_ids(self) -> frozenset[int]:
        """Standard ids of the frames this device sends (feedback / replies)."""

    # -- public API (called by the channel / world) --------------------------------------

    @property
    def faults(self) -> dict[FaultKind, Fault]:
        """Active faults by kind (a copy)."""
        return dict(self._faults)

    @property
    def online(self) -> bool:
        """False while an OFFLINE fault is active."""
        return FaultKind.OFFLINE not in self._faults

    def receive(
        self,
        arbitration_id: int,
        data: bytes,
        now_ns: int,
        *,
        is_extended_id: bool = False,
        is_remote_frame: bool = False,
        is_fd: bool = False,
    ) -> list[Frame]:
        """Hand the device a frame seen on the bus; return the frames it answers with.

        Args:
            arbitration_id: the frame's id.
            data: the frame's data bytes.
            now_ns: simulation time [ns].
            is_extended_id: 29-bit frame (the real drivers only read 11-bit frames).
            is_remote_frame: remote (RTR) frame.
            is_fd: CAN FD frame (the real drivers are classic CAN only).

        Returns:
            Reply frames, possibly none.
        """
        if (self._faults and not self.online) or arbitration_id not in self.listen_ids:
            return []
        if is_extended_id or is_remote_frame or is_fd:
            self.stats.ignored_frames += 1
            return []
        try:
            replies = self._on_frame(arbitration_id, bytes(data), now_ns)
        except ProtocolError:
            self.stats.ignored_frames += 1
            return []
        if replies is None:
            self.stats.ignored_frames += 1
            return []
        self.stats.rx_frames += 1
        self.stats.tx_frames += len(replies)
        return replies

    def control(self, now_ns: int, dt: float) -> None:
        """Run the driver's own logic before a physics step (timeouts, internal loops)."""
        self._control(now_ns, dt)

    def step(self, dt: float, stator_acceleration: float = 0.0) -> None:
        """Advance the physics by dt [s] (see :meth:`MotorModel.step`)."""
        self.model.step(dt, stator_acceleration=stator_acceleration)

    def emit(self, now_ns: int) -> list[Frame]:
        """Return the frames the device sends on its own at this tick (feedback, garbage)."""
        faults = self._faults  # usually empty: skip the enum lookups then
        if faults and not self.online:
            return []
        frames = self._periodic(now_ns)
        if frames:
            self.stats.tx_frames += len(frames)
        garbage = faults.get(FaultKind.GARBAGE) if faults else None
        if garbage is not None and self._garbage is not None and self._garbage.due(now_ns):
            if garbage.can_id is not None:
                can_id = garbage.can_id
            elif garbage.random_ids:
                can_id = self._rng.randrange(_STD_ID_MAX + 1)
            else:
                can_id = min(self.transmit_ids)
            frames.append((can_id, self._rng.randbytes(8)))
            self.stats.garbage_frames += 1
        return frames

    def inject(self, fault: Fault) -> None:
        """Activate a fault (replacing one of the same kind); it acts from the next tick."""
        self._faults[fault.kind] = fault
        if fault.kind is FaultKind.JAM:
            self.model.locked = fault.load_torque is None
            self.model.brake_torque = fault.load_torque or 0.0
        elif fault.kind is FaultKind.OVER_TEMPERATURE:
            self.model.temperature_override = fault.temperature
            self.model.temperature = fault.temperature
        elif fault.kind is FaultKind.GARBAGE:
            self._garbage = RateSchedule(fault.rate_hz)

    def clear_faults(self, kind: FaultKind | None = None) -> None:
        """Remove one kind of fault, or all of them (None).

        The temperature is not reset: after an over-temperature it cools down from the
        forced value through the thermal model.
        """
        kinds = list(self._faults) if kind is None else [kind]
        for k in kinds:
            self._faults.pop(k, None)
            if k is FaultKind.JAM:
                self.model.locked = False
                self.model.brake_torque = 0.0
            elif k is FaultKind.OVER_TEMPERATURE:
                self.model.temperature_override = None
            elif k is FaultKind.GARBAGE:
                self._garbage = None

    @property
    def overheated(self) -> bool:
        """True while the winding is above the driver's cut-out temperature."""
        return self.overtemp_c is not None and self.model.temperature > self.overtemp_c

    # -- hooks -----------------------------------------------------------------------------

    @abstractmethod
    def _on_frame(self, arbitration_id: int, data: bytes, now_ns: int) -> list[Frame] | None:
        """Use a frame on one of :attr:`listen_ids`; return replies, or None to ignore it.

        Raises:
            ProtocolError: the bytes cannot be decoded (the frame is then ignored).
        """

    def _control(self, now_ns: int, dt: float) -> None:  # noqa: B027 (optional hook)
        """Per-tick driver logic before the physics step; nothing by default."""

    @abstractmethod
    def _periodic(self, now_ns: int) -> list[Frame]:
        """Frames the device sends unasked at this tick."""


# -- DJI -------------------------------------------------------------------------------------


class DjiDevice(SimDevice):
    """A DJI motor with its ESC: C620 + M3508, C610 + M2006, or GM6020 (voltage/current).

    Attributes:
        spec: ids, limits and scales (from :func:`rm_base.hardware.protocols.dji.make_dji_spec`).
        command_timeout_ns: no command for this long -> zero current; None never.
        command_raw: the last raw value taken from the motor's slot.
    """

    family = 'dji'

    def __init__(
        self,
        name: str,
        motor_type: MotorType,
        motor_id: int,
        model: MotorModel,
        spec: dji.DjiSpec,
        *,
        feedback_rate_hz: float = 1000.0,
        command_timeout: float | None = 0.1,
        seed: int = 0,
        overtemp_c: float | None = None,
    ):
        """Create the device; see :func:`device_from_config` for the parameters."""
        super().__init__(name, motor_type, motor_id, model, seed=seed, overtemp_c=overtemp_c)
        self.spec = spec
        self.command_id, self.slot = spec.command_slot(motor_id)
        self.feedback_id = spec.feedback_id(motor_id)
        self.command_timeout_ns = (
            None if not command_timeout else round(command_timeout * _NS_PER_S)
        )
        self.command_raw = 0
        self._voltage_control = spec.command_unit == 'V'
        self._last_command_ns: int | None = None
        self._timed_out = True
        self._feedback = RateSchedule(
            feedback_rate_hz, first_ns=round(_NS_PER_S / feedback_rate_hz)
        )
        self._listen = frozenset({self.command_id})
        self._transmit = frozenset({self.feedback_id})

    @property
    def command_raw(self) -> int:
        """The last raw value taken from the motor's slot."""
        return self._command_raw

    @command_raw.setter
    def command_raw(self, raw: int) -> None:
        self._command_raw = raw
        self._command_si = self.spec.si_from_raw(raw)  # in A or V, applied every tick

    @property
    def listen_ids(self) -> frozenset[int]:
        """The group command frame that holds this motor's slot."""
        return self._listen

    @property
    def transmit_ids(self) -> frozenset[int]:
        """The feedback id (0x200 + id, or 0x204 + id for the GM6020)."""
        return self._transmit

    def _on_frame(self, arbitration_id: int, data: bytes, now_ns: int) -> list[Frame] | None:
        raw = dji.unpack_command(data)[self.slot]
        limit = self.spec.raw_limit
        # The ESC saturates out-of-range values rather than wrapping them.
        self.command_raw = max(-limit, min(limit, raw))
        self._last_command_ns = now_ns
        self._timed_out = False
        self._apply(self._command_si)
        return []

    def _apply(self, value: float) -> None:
        if self._voltage_control:
            self.model.command_voltage(value)
        else:
            self.model.command_current(value)

    def _control(self, now_ns: int, dt: float) -> None:
        if self._timed_out:
            self.model.command_current(0.0)
            return
        timeout = self.command_timeout_ns
        last = self._last_command_ns
        if timeout is not None and last is not None and now_ns - last > timeout:
            self._timed_out = True
            self.stats.timeouts += 1
            self.model.command_current(0.0)
        elif self.overheated:
            self.model.command_current(0.0)
        else:
            # Re-applied each tick: an over-temperature cut-out may have zeroed the output.
            self._apply(self._command_si)

    def _periodic(self, now_ns: int) -> list[Frame]:
        if not self._feedback.due(now_ns):
            return []
        m = self.model
        current_raw = round(m.current / self.spec.feedback_amps_per_raw)
        current_raw = max(dji.INT16_MIN, min(dji.INT16_MAX, current_raw))
        temperature = None
        if self.spec.has_temperature:
            temperature = max(0, min(255, round(m.temperature)))
        data = dji.encode_feedback(
            m.encoder_count, dji.rpm_from_rad_per_s(m.rotor_velocity), current_raw, temperature
        )
        return [(self.feedback_id, data)]


# -- Damiao / Cheetah ------------------------------------------------------------------------


class _MitDevice(SimDevice):
    """Shared behaviour of motors that run the MIT law themselves and reply on command."""

    def __init__(
        self,
        name: str,
        motor_type: MotorType,
        motor_id: int,
        model: MotorModel,
        limits: mit.MitLimits,
        *,
        master_id: int,
        enabled: bool = False,
        seed: int = 0,
        overtemp_c: float | None = None,
    ):
        super().__init__(name, motor_type, motor_id, model, seed=seed, overtemp_c=overtemp_c)
        self.limits = limits
        self.master_id = master_id
        self.enabled = enabled
        #: Output angle [rad] at which the reported position is 0 (set-zero frame).
        self.zero_offset = 0.0
        self.command: mit.MitCommand = mit.MitCommand(0.0, 0.0, 0.0, 0.0, 0.0)
        self._last_command_ns: int | None = None

    @property
    def transmit_ids(self) -> frozenset[int]:
        """The master id the replies go to."""
        return frozenset({self.master_id})

    @property
    def position(self) -> float:
        """Output position relative to the zero set on the motor [rad]."""
        return self.model.angle - self.zero_offset

    def _apply_mit(self, cmd: mit.MitCommand) -> None:
        self.model.command_impedance(
            cmd.position,
            cmd.velocity,
            max(0.0, cmd.kp),
            max(0.0, cmd.kd),
            cmd.torque,
            position_offset=self.zero_offset,
        )

    def _limp(self) -> None:
        self.model.command_current(0.0)

    def _enable(self) -> None:
        # A stale command from before the enable is not replayed: start limp.
        self.command = mit.MitCommand(0.0, 0.0, 0.0, 0.0, 0.0)
        self.enabled = True
        self._limp()

    def _disable(self) -> None:
        self.enabled = False
        self._limp()

    def _set_zero(self) -> None:
        self.zero_offset = self.model.angle
        if self.enabled:
            self._apply_mit(self.command)

    def _periodic(self, now_ns: int) -> list[Frame]:
        return []  # these motors only speak when spoken to

    @abstractmethod
    def _reply(self) -> Frame:
        """The feedback frame sent in answer to a command."""


class DamiaoDevice(_MitDevice):
    """A Damiao motor (DM4310, DM8009, ...) in MIT, POS_VEL or VEL mode.

    Attributes:
        mode: the motor's control mode (CTRL_MODE register).
        error: latched error state, or None.
        command_timeout_ns: the TIMEOUT register: enabled and no command for this long ->
            COMMUNICATION_LOST; None disables it (the factory default).
        vel_kp: internal velocity loop gain [N·m·s/rad] (POS_VEL, VEL).
        vel_ki: internal velocity loop integral gain [N·m/rad].
        pos_kp: internal position loop gain [1/s] (POS_VEL).
    """

    family = 'damiao'

    def __init__(
        self,
        name: str,
        motor_type: MotorType,
        motor_id: int,
        model: MotorModel,
        limits: mit.MitLimits,
        *,
        master_id: int,
        mode: damiao.DmMode = damiao.DmMode.MIT,
        enabled: bool = False,
        command_timeout: float | None = None,
        vel_kp: float | None = None,
        vel_ki: float | None = None,
        pos_kp: float = 20.0,
        seed: int = 0,
        overtemp_c: float | None = 120.0,
    ):
        """Create the device; see :func:`device_from_config` for the parameters."""
        super().__init__(
            name,
            motor_type,
            motor_id,
            model,
            limits,
            master_id=master_id,
            enabled=enabled,
            seed=seed,
            overtemp_c=overtemp_c,
        )
        if mode not in (damiao.DmMode.MIT, damiao.DmMode.POS_VEL, damiao.DmMode.VEL):
            raise SimConfigError(f'{name}: Damiao mode {mode.name} is not simulated')
        self.mode = mode
        self.command_id = damiao.command_id(motor_id, mode)
        self.error: damiao.DmState | None = None
        self.command_timeout_ns = (
            None if not command_timeout else round(command_timeout * _NS_PER_S)
        )
        # Internal loops: about 100 rad/s velocity bandwidth on the configured inertia.
        bandwidth = 100.0
        self.vel_kp = model.params.output_inertia * bandwidth if vel_kp is None else vel_kp
        self.vel_ki = self.vel_kp * bandwidth / 4.0 if vel_ki is None else vel_ki
        self.pos_kp = pos_kp
        self._target_position = 0.0
        self._target_velocity = 0.0
        self._velocity_limit = 0.0
        self._integral = 0.0
        # System frames are accepted on the bare id and on id + mode offset (docs/PROTOCOLS.md
        # §2.2: the official SDKs disagree).
        self._listen = frozenset({motor_id, self.command_id})

    @property
    def listen_ids(self) -> frozenset[int]:
        """The bare id and the mode's command id."""
        return self._listen

    @property
    def state(self) -> damiao.DmState:
        """The state nibble the motor reports."""
        if self.error is not None:
            return self.error
        return damiao.DmState.ENABLED if self.enabled else damiao.DmState.DISABLED

    def _on_frame(self, arbitration_id: int, data: bytes, now_ns: int) -> list[Frame] | None:
        system = mit.parse_system_frame(data) if len(data) == mit.FRAME_LENGTH else None
        if system is not None:
            self._system(system)
            return [self._reply()]
        if arbitration_id != self.command_id:
            return None  # a control frame on the bare id of a non-MIT motor
        if self.mode is damiao.DmMode.MIT:
            command = mit.unpack_mit_command(data, self.limits)
        elif self.mode is damiao.DmMode.POS_VEL:
            position, velocity_limit = damiao.unpack_pos_vel(data)
            _require_finite((position, velocity_limit))
        else:
            velocity = damiao.unpack_vel(data)
            _require_finite((velocity,))
        if not self.enabled:
            return None
        self._last_command_ns = now_ns
        if self.mode is damiao.DmMode.MIT:
            self.command = command
            if self.error is None:
                self._apply_mit(command)
        elif self.mode is damiao.DmMode.POS_VEL:
            self._target_position = position
            self._velocity_limit = abs(velocity_limit)
        else:
            self._target_velocity = velocity
        return [self._reply()]

    def _system(self, command: mit.SystemCommand) -> None:
        if command is mit.SystemCommand.ENABLE:
            if self.error is None:
                self._enable()
                self._integral = 0.0
                self._target_position = self.position
                self._target_velocity = 0.0
                self._velocity_limit = 0.0
        elif command is mit.SystemCommand.DISABLE:
            self._disable()
        elif command is mit.SystemCommand.SET_ZERO:
            self._target_position -= self.model.angle - self.zero_offset
            self._set_zero()
        elif command is mit.SystemCommand.CLEAR_ERROR and self.error is not None:
            if not self._error_condition():
                self.error = None
                self._disable()

    def _error_condition(self) -> damiao.DmState | None:
        if self.overheated:
            return damiao.DmState.COIL_OVER_TEMPERATURE
        return None

    def _control(self, now_ns: int, dt: float) -> None:
        if self.error is None and self.enabled:
            self.error = self._error_condition()
            timeout = self.command_timeout_ns
            last = self._last_command_ns
            if self.error is None and timeout is not None and last is not None:
                if now_ns - last > timeout:
                    self.error = damiao.DmState.COMMUNICATION_LOST
                    self.stats.timeouts += 1
        if self.error is not None or not self.enabled:
            self._limp()
            return
        if self.mode is damiao.DmMode.MIT:
            return  # the MIT law set by the last command stays in force
        if self.mode is damiao.DmMode.POS_VEL:
            error = self._target_position - self.position
            limit = self._velocity_limit
            target = max(-limit, min(limit, self.pos_kp * error))
        else:
            target = self._target_velocity
        # PI velocity loop; the P part is implicit in the physics (kd), the I part explicit
        # and clamped to the torque range against wind-up.
        t_max = self.limits.t_max
        self._integral += self.vel_ki * (target - self.model.velocity) * dt
        self._integral = max(-t_max, min(t_max, self._integral))
        self.model.command_impedance(0.0, target, 0.0, self.vel_kp, self._integral)

    def _reply(self) -> Frame:
        m = self.model
        p_max = self.limits.p_max
        # The reported position wraps within ±PMAX (it is a 16-bit field over that range).
        position = (self.position + p_max) % (2.0 * p_max) - p_max
        ambient = m.params.ambient_temperature
        # No separate model of the driver board: its MOSFETs run halfway between ambient
        # and the winding.
        t_mos = ambient + 0.5 * (m.temperature - ambient)
        data = damiao.encode_feedback(
            self.motor_id & damiao.MAX_MOTOR_ID,
            int(self.state),
            position=position,
            velocity=m.velocity,
            torque=m.torque,
            t_mos=max(0, min(255, round(t_mos))),
            t_rotor=max(0, min(255, round(m.temperature))),
            limits=self.limits,
        )
        return (self.master_id, data)


class CheetahDevice(_MitDevice):
    """A motor running Ben Katz's MIT Cheetah firmware.

    Attributes:
        reply_voltage: send the 7-byte reply with bus voltage (STM32 firmware) instead of
            the 6-byte one (mbed firmware).
    """

    family = 'cheetah'

    def __init__(
        self,
        name: str,
        motor_type: MotorType,
        motor_id: int,
        model: MotorModel,
        limits: mit.MitLimits,
        *,
        master_id: int = cheetah.DEFAULT_MASTER_ID,
        enabled: bool = False,
        reply_voltage: bool = False,
        seed: int = 0,
        overtemp_c: float | None = None,
    ):
        """Create the device; see :func:`device_from_config` for the parameters."""
        super().__init__(
            name,
            motor_type,
            motor_id,
            model,
            limits,
            master_id=master_id,
            enabled=enabled,
            seed=seed,
            overtemp_c=overtemp_c,
        )
        self.reply_voltage = reply_voltage
        self._listen = frozenset({motor_id})

    @property
    def listen_ids(self) -> frozenset[int]:
        """The motor's CAN id."""
        return self._listen

    def _on_frame(self, arbitration_id: int, data: bytes, now_ns: int) -> list[Frame] | None:
        system = mit.parse_system_frame(data)
        # The firmware knows only FC/FD/FE; anything else (FF..FB too) is an MIT command.
        if system in cheetah.CHEETAH_SYSTEM_COMMANDS:
            if system is mit.SystemCommand.ENABLE:
                self._enable()
            elif system is mit.SystemCommand.DISABLE:
                self._disable()
            else:
                self._set_zero()
            return [self._reply()]
        command = mit.unpack_mit_command(data, self.limits)
        if not self.enabled:
            return None
        self._last_command_ns = now_ns
        self.command = command
        if not self.overheated:
            self._apply_mit(command)
        return [self._reply()]

    def _control(self, now_ns: int, dt: float) -> None:
        if not self.enabled or self.overheated:
            self._limp()
        elif self.model.mode is DriveMode.CURRENT:
            self._apply_mit(self.command)  # back from an over-temperature cut-out

    def _reply(self) -> Frame:
        m = self.model
        data = cheetah.encode_reply(
            self.motor_id & 0xFF,
            position=self.position,
            velocity=m.velocity,
            torque=m.torque,
            bus_voltage=m.params.supply_voltage if self.reply_voltage else None,
            limits=self.limits,
        )
        return (self.master_id, data)


def _require_finite(values: tuple[float, ...]) -> None:
    if not all(math.isfinite(v) for v in values):
        raise ValueRangeError(f'non-finite value in command {values!r}')


# -- config ----------------------------------------------------------------------------------

_DJI_KINDS = {
    MotorType.M3508: dji.DjiKind.C620,
    MotorType.M2006: dji.DjiKind.C610,
}
_DM_MODELS = {MotorType.DM4310: 'DM4310', MotorType.DM8009: 'DM8009'}
_PARAM_KEYS = frozenset(MotorParams.__dataclass_fields__)
_COMMON_KEYS = frozenset(
    {'type', 'id', 'name', 'initial_position', 'initial_velocity', 'overtemp_c'}
)
_FAMILY_KEYS = {
    'dji': frozenset(
        {
            'feedback_rate_hz',
            'command_timeout',
            'control',
            'raw_limit',
            'si_per_raw',
            'feedback_amps_per_raw',
        }
    ),
    'damiao': frozenset(
        {
            'model',
            'master_id',
            'mode',
            'limits',
            'enabled',
            'command_timeout',
            'vel_kp',
            'vel_ki',
            'pos_kp',
        }
    ),
    'cheetah': frozenset({'master_id', 'limits', 'enabled', 'reply_voltage'}),
}


def _number(cfg: Mapping[str, Any], key: str, default: float | None, name: str) -> float | None:
    value = cfg.get(key, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SimConfigError(f'{name}: {key} must be a finite number, got {value!r}')
    return float(value)


def _int_id(cfg: Mapping[str, Any], key: str, name: str, default: int | None = None) -> int:
    value = cfg.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= _STD_ID_MAX:
        raise SimConfigError(f'{name}: {key} must be an int in 0..0x7FF, got {value!r}')
    return value


def device_from_config(config: Mapping[str, Any], *, seed: int = 0) -> SimDevice:
    """Build a simulated motor from a plain dict.

    Keys (SI units; every key but ``type`` and ``id`` is optional):

    * ``type``: ``'m3508' | 'm2006' | 'gm6020' | 'dm4310' | 'dm8009' | 'cheetah'``.
    * ``id``: ESC id (DJI: C620/C610 1..8, GM6020 1..7) or CAN id (Damiao, Cheetah).
    * ``name``: unique name, default ``'<type>_<id>'``.
    * any :class:`~rm_base.sim.motor.MotorParams` field, e.g. ``load_inertia`` [kg·m²],
      ``viscous_friction`` [N·m·s/rad], ``coulomb_friction`` [N·m], ``max_current`` [A].
    * ``initial_position`` [rad] and ``initial_velocity`` [rad/s] at the output shaft.
    * ``overtemp_c``: cut-out temperature [°C]; default none for DJI and Cheetah,
      120 °C for Damiao (which then reports COIL_OVER_TEMPERATURE).
    * DJI: ``feedback_rate_hz`` (1000), ``command_timeout`` [s] (0.1; 0 or None = never),
      ``control`` (GM6020: ``'voltage'`` (default) or ``'current'``), and the
      UNVERIFIED scales of :func:`rm_base.hardware.protocols.dji.make_dji_spec`:
      ``raw_limit``, ``si_per_raw``, ``feedback_amps_per_raw``.
    * Damiao: ``model`` (default from the type, e.g. ``'DM4310'``), ``master_id``
      (default id + 0x10), ``mode`` (``'mit'`` default, ``'pos_vel'``, ``'vel'``),
      ``limits`` (``{'p_max': .., 'v_max': .., 't_max': ..}`` overrides), ``enabled``
      (False), ``command_timeout`` [s] (None), ``vel_kp``, ``vel_ki``, ``pos_kp``.
    * Cheetah: ``master_id`` (0), ``limits`` (default P ±12.5, V ±65, T ±18),
      ``enabled`` (False), ``reply_voltage`` (False: 6-byte reply).

    Args:
        config: the motor's dict.
        seed: seed of the device's random generator (garbage frames).

    Returns:
        The device.

    Raises:
        SimConfigError: a missing, unknown or invalid key.
    """
    if not isinstance(config, Mapping):
        raise SimConfigError(f'a motor config must be a mapping, got {config!r}')
    if 'type' not in config or 'id' not in config:
        raise SimConfigError(f'a motor config needs a type and an id, got {dict(config)!r}')
    try:
        motor_type = MotorType(config['type'])
    except ValueError:
        known = sorted(t.value for t in MotorType)
        raise SimConfigError(f'unknown motor type {config["type"]!r}; known: {known}') from None
    motor_id = _int_id(config, 'id', f'{motor_type.value} motor')
    name = config.get('name', f'{motor_type.value}_{motor_id}')
    if not isinstance(name, str) or not name:
        raise SimConfigError(f'motor name must be a non-empty string, got {name!r}')
    family = motor_type.family
    allowed = _COMMON_KEYS | _PARAM_KEYS | _FAMILY_KEYS[family]
    unknown = sorted(set(config) - allowed)
    if unknown:
        raise SimConfigError(f'{name}: unknown key(s) {unknown}; known: {sorted(allowed)}')

    params = motor_params(motor_type, **{k: config[k] for k in _PARAM_KEYS & set(config)})
    model = MotorModel(
        params,
        angle=_number(config, 'initial_position', 0.0, name),
        velocity=_number(config, 'initial_velocity', 0.0, name),
    )
    common: dict[str, Any] = {'seed': seed}
    if 'overtemp_c' in config:
        common['overtemp_c'] = _number(config, 'overtemp_c', None, name)
    parts = {
        'name': name,
        'motor_type': motor_type,
        'motor_id': motor_id,
        'model': model,
        'common': common,
    }
    try:
        if family == 'dji':
            return _dji_from_config(config, **parts)
        if family == 'damiao':
            return _damiao_from_config(config, **parts)
        return _cheetah_from_config(config, **parts)
    except (HardwareConfigError, ValueRangeError) as err:
        raise SimConfigError(f'{name}: {err}') from err


def _dji_from_config(
    cfg: Mapping[str, Any],
    *,
    name: str,
    motor_type: MotorType,
    motor_id: int,
    model: MotorModel,
    common: dict[str, Any],
) -> DjiDevice:
    control = cfg.get('control', 'voltage')
    if motor_type is MotorType.GM6020:
        if control not in ('voltage', 'current'):
            raise SimConfigError(f"{name}: control must be 'voltage' or 'current', got {control!r}")
        kind = dji.DjiKind.GM6020_VOLTAGE if control == 'voltage' else dji.DjiKind.GM6020_CURRENT
    elif 'control' in cfg:
        raise SimConfigError(f'{name}: only the GM6020 has a control mode')
    else:
        kind = _DJI_KINDS[motor_type]
    spec = dji.make_dji_spec(
        kind,
        raw_limit=cfg.get('raw_limit'),
        si_per_raw=cfg.get('si_per_raw'),
        feedback_amps_per_raw=cfg.get('feedback_amps_per_raw'),
    )
    spec.check_id(motor_id)
    rate = _number(cfg, 'feedback_rate_hz', 1000.0, name)
    if rate is None or rate <= 0.0:
        raise SimConfigError(f'{name}: feedback_rate_hz must be > 0, got {rate}')
    timeout = _number(cfg, 'command_timeout', 0.1, name)
    if timeout is not None and timeout < 0.0:
        raise SimConfigError(f'{name}: command_timeout must be >= 0 s, got {timeout}')
    return DjiDevice(
        name,
        motor_type,
        motor_id,
        model,
        spec,
        feedback_rate_hz=rate,
        command_timeout=timeout,
        **common,
    )


def _limits(cfg: Mapping[str, Any], base: mit.MitLimits, name: str) -> mit.MitLimits:
    overrides = cfg.get('limits')
    if overrides is not None and not isinstance(overrides, Mapping):
        raise SimConfigError(f'{name}: limits must be a mapping, got {overrides!r}')
    return base.with_overrides(dict(overrides) if overrides else None)


def _flag(cfg: Mapping[str, Any], key: str, name: str) -> bool:
    value = cfg.get(key, False)
    if not isinstance(value, bool):
        raise SimConfigError(f'{name}: {key} must be true or false, got {value!r}')
    return value


def _damiao_from_config(
    cfg: Mapping[str, Any],
    *,
    name: str,
    motor_type: MotorType,
    motor_id: int,
    model: MotorModel,
    common: dict[str, Any],
) -> DamiaoDevice:
    if motor_id > damiao.MAX_MOTOR_ID:
        # The feedback carries only the low nibble of the id.
        raise SimConfigError(f'{name}: Damiao id must be 0..15, got {motor_id}')
    dm_model = cfg.get('model', _DM_MODELS[motor_type])
    if not isinstance(dm_model, str):
        raise SimConfigError(f'{name}: model must be a string, got {dm_model!r}')
    limits = _limits(cfg, damiao.dm_limits(dm_model), name)
    mode_name = cfg.get('mode', 'mit')
    modes = {'mit': damiao.DmMode.MIT, 'pos_vel': damiao.DmMode.POS_VEL, 'vel': damiao.DmMode.VEL}
    if mode_name not in modes:
        raise SimConfigError(f'{name}: mode must be one of {sorted(modes)}, got {mode_name!r}')
    timeout = _number(cfg, 'command_timeout', None, name)
    if timeout is not None and timeout < 0.0:
        raise SimConfigError(f'{name}: command_timeout must be >= 0 s, got {timeout}')
    gains = {k: _number(cfg, k, None, name) for k in ('vel_kp', 'vel_ki')}
    for key, value in gains.items():
        if value is not None and value < 0.0:
            raise SimConfigError(f'{name}: {key} must be >= 0, got {value}')
    pos_kp = _number(cfg, 'pos_kp', 20.0, name)
    if pos_kp is None or pos_kp < 0.0:
        raise SimConfigError(f'{name}: pos_kp must be >= 0, got {pos_kp}')
    return DamiaoDevice(
        name,
        motor_type,
        motor_id,
        model,
        limits,
        master_id=_int_id(cfg, 'master_id', name, default=motor_id + 0x10),
        mode=modes[mode_name],
        enabled=_flag(cfg, 'enabled', name),
        command_timeout=timeout,
        vel_kp=gains['vel_kp'],
        vel_ki=gains['vel_ki'],
        pos_kp=pos_kp,
        **common,
    )


def _cheetah_from_config(
    cfg: Mapping[str, Any],
    *,
    name: str,
    motor_type: MotorType,
    motor_id: int,
    model: MotorModel,
    common: dict[str, Any],
) -> CheetahDevice:
    return CheetahDevice(
        name,
        motor_type,
        motor_id,
        model,
        _limits(cfg, cheetah.CHEETAH_DEFAULT_LIMITS, name),
        master_id=_int_id(cfg, 'master_id', name, default=cheetah.DEFAULT_MASTER_ID),
        enabled=_flag(cfg, 'enabled', name),
        reply_voltage=_flag(cfg, 'reply_voltage', name),
        **common,
    )


def check_channel(devices: list[SimDevice]) -> None:
    """Check that the devices can share one bus: no two send on one id, no command clash.

    Raises:
        SimConfigError: two devices use one feedback id or one DJI command slot, or one
            device's command id is another one's feedback id; the message names both.
    """
    djis = [d for d in devices if isinstance(d, DjiDevice)]
    try:
        dji.check_collisions([(d.spec.kind, d.motor_id) for d in djis], [d.name for d in djis])
    except (HardwareConfigError, ValueRangeError) as err:
        raise SimConfigError(str(err)) from err
    names: dict[str, SimDevice] = {}
    sent: dict[int, SimDevice] = {}
    for dev in devices:
        if dev.name in names:
            raise SimConfigError(f'two motors are named {dev.name!r}')
        names[dev.name] = dev
        for can_id in dev.transmit_ids:
            if can_id in sent:
                raise SimConfigError(
                    f'{dev.name} and {sent[can_id].name} both send on id 0x{can_id:03X}'
                )
            sent[can_id] = dev
    listened: dict[int, SimDevice] = {}
    for dev in devices:
        for can_id in dev.listen_ids:
            if can_id in sent:
                raise SimConfigError(
                    f'{dev.name} listens on 0x{can_id:03X}, where {sent[can_id].name} sends'
                )
            other = listened.get(can_id)
            # DJI ESCs share group frames by design (distinct slots, checked above).
            if other is not None and not (isinstance(other, DjiDevice) and dev in djis):
                raise SimConfigError(
                    f'{dev.name} and {other.name} both take commands on 0x{can_id:03X}'
                )
            listened[can_id] = dev
