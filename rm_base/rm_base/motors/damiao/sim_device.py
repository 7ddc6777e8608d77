"""Simulated Damiao motor (DM4310, DM8009...).

Answers each command frame with one feedback frame, but only while enabled; system frames
(enable, disable, set zero, clear error) are always answered. MIT law computed on the
motor; POS_VEL and VEL modes with internal loops. Over-temperature and (optional) command
timeout latch an error code until cleared.
"""

from __future__ import annotations

from rm_base.hardware.protocols import mit
from rm_base.motors.damiao import protocol as damiao
from rm_base.sim_devices.device import NS_PER_S, Frame, require_finite
from rm_base.sim_devices.errors import SimConfigError
from rm_base.sim_devices.mit_device import MitDevice
from rm_base.sim_devices.motor import MotorModel
from rm_base.sim_devices.motor_params import MotorType


class DamiaoDevice(MitDevice):
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
            None if not command_timeout else round(command_timeout * NS_PER_S)
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
            require_finite((position, velocity_limit))
        else:
            velocity = damiao.unpack_vel(data)
            require_finite((velocity,))
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
