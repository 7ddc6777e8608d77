"""Simulated LK-TECH MF/MG motor: answers every request on 0x140 + id from the same id.

Torque (0xA1) drives the winding current; speed (0xA2) and the position commands
(0xA3..0xA8) run the motor's own loops (a position P loop into a PI speed loop, the speed
limited as asked). OFF (0x80) and STOP (0x81) take the output away (OFF also forgets the
multi-turn count), RUN (0x88) gives it back. Status 1 reports the supply voltage, the
state and the error bits: over-temperature while the winding is over its cut-out,
under-voltage below ``min_voltage``. Like the real motor, it keeps its last command when
no further one comes.
"""

from __future__ import annotations

import math

from rm_base.motors.lk import protocol as lk
from rm_base.sim_devices.device import Frame, SimDevice, require_finite
from rm_base.sim_devices.motor import MotorModel

_DEG = 180.0 / math.pi


class LkDevice(SimDevice):
    """An LK motor and its driver.

    Attributes:
        scale: the current scale its firmware counts iq in.
        encoder_bits: width of the encoder in its replies.
        on: the motor state (RUN, not OFF or STOP).
        supply_voltage: what status 1 reports [V] (a test may lower it).
        min_voltage: below it the under-voltage bit is set and the output is off [V].
    """

    def __init__(self, name: str, motor_type: str, motor_id: int, model: MotorModel, *,
                 scale: lk.CurrentScale, encoder_bits: int = 16, min_voltage: float = 18.0,
                 speed_kp: float | None = None, speed_ki: float | None = None,
                 position_kp: float = 20.0, seed: int = 0,
                 overtemp_c: float | None = 120.0) -> None:
        """Create the device; see the family's schema for the parameters."""
        super().__init__(name, motor_type, motor_id, model, seed=seed, overtemp_c=overtemp_c)
        self.command_id = lk.motor_frame_id(motor_id)
        self.scale = scale
        self.encoder_bits = encoder_bits
        self.on = True
        self.supply_voltage = model.params.supply_voltage
        self.min_voltage = min_voltage
        bandwidth = 100.0  # [rad/s] of the speed loop on the configured inertia
        self.speed_kp = model.params.output_inertia * bandwidth if speed_kp is None else speed_kp
        self.speed_ki = self.speed_kp * bandwidth / 4.0 if speed_ki is None else speed_ki
        self.position_kp = position_kp
        self.requests = 0
        self._loop: lk.Command = lk.Command.TORQUE
        self._amps = 0.0
        self._target_velocity = 0.0  # [rad/s] at the output
        self._target_position = 0.0  # [rad] at the output
        self._speed_limit = math.inf
        self._integral = 0.0
        self._turn_origin = 0.0  # output angle that OFF made the multi-turn zero
        self._ids = frozenset({self.command_id})

    @property
    def listen_ids(self) -> frozenset[int]:
        """0x140 + id."""
        return self._ids

    @property
    def transmit_ids(self) -> frozenset[int]:
        """The same id."""
        return self._ids

    @property
    def error(self) -> int:
        """The error bits status 1 reports now."""
        bits = 0
        if self.supply_voltage < self.min_voltage:
            bits |= lk.ErrorState.UNDER_VOLTAGE
        if self.overheated:
            bits |= lk.ErrorState.OVER_TEMPERATURE
        return bits

    def _on_frame(self, arbitration_id: int, data: bytes, now_ns: int) -> list[Frame] | None:
        request = lk.unpack_request(data)
        self.requests += 1
        cmd = request.command
        if cmd in lk.STATUS_REPLIES:
            return [(self.command_id, self._status(cmd))]
        if cmd in lk.ECHO_REPLIES:
            self._state(cmd)
            return [(self.command_id, bytes(data))]
        if cmd is not lk.Command.READ_STATUS_2:
            self._command(request)
        return [(self.command_id, self._motion(cmd))]

    def _state(self, cmd: lk.Command) -> None:
        if cmd is lk.Command.RUN:
            self.on = True
            return
        self.on = False
        self._loop, self._amps, self._integral = lk.Command.TORQUE, 0.0, 0.0
        if cmd is lk.Command.MOTOR_OFF:
            self._turn_origin = self.model.angle

    def _command(self, request: lk.Request) -> None:
        cmd, value = request.command, request.value
        limit = math.inf if request.max_dps is None else request.max_dps / _DEG
        if cmd is lk.Command.TORQUE:
            iq = max(-self.scale.command_limit, min(self.scale.command_limit, value))
            self._amps = iq * self.scale.command_amps
        elif cmd is lk.Command.SPEED:
            self._target_velocity = value * lk.CENTI / _DEG / self.model.params.gear_ratio
        elif cmd in (lk.Command.MULTI_TURN, lk.Command.MULTI_TURN_LIMITED):
            self._target_position = self._turn_origin + self._output(value)
        elif cmd in (lk.Command.SINGLE_TURN, lk.Command.SINGLE_TURN_LIMITED):
            # the nearest angle that is the asked one within a rotor turn (the asked
            # direction is not modelled)
            span = 2.0 * math.pi / self.model.params.gear_ratio
            here = self.model.angle - self._turn_origin
            step = math.remainder(self._output(value) - here, span)
            self._target_position = self.model.angle + step
        else:
            self._target_position = self.model.angle + self._output(value)
        require_finite((self._amps, self._target_velocity, self._target_position))
        loop = cmd if cmd in (lk.Command.TORQUE, lk.Command.SPEED) else lk.Command.MULTI_TURN
        if loop is not self._loop:
            self._integral = 0.0
        self._loop = loop
        self._speed_limit = limit / self.model.params.gear_ratio

    def _output(self, centi_deg: int) -> float:
        """A commanded rotor angle [0.01 deg] at the output [rad]."""
        return centi_deg * lk.CENTI / _DEG / self.model.params.gear_ratio

    def _control(self, now_ns: int, dt: float) -> None:
        m = self.model
        if not self.on or self.error:
            m.command_current(0.0)
            return
        if self._loop is lk.Command.TORQUE:
            m.command_current(self._amps)
            return
        if self._loop is lk.Command.SPEED:
            target = self._target_velocity
        else:
            target = self.position_kp * (self._target_position - m.angle)
        target = max(-self._speed_limit, min(self._speed_limit, target))
        t_max = m.params.max_current * m.params.torque_constant
        self._integral += self.speed_ki * (target - m.velocity) * dt
        self._integral = max(-t_max, min(t_max, self._integral))
        m.command_impedance(0.0, target, 0.0, self.speed_kp, self._integral)

    def _motion(self, cmd: lk.Command) -> bytes:
        m = self.model
        ticks = 1 << self.encoder_bits
        turns = m.rotor_angle / (2.0 * math.pi)
        encoder = math.floor((turns - math.floor(turns)) * ticks) % ticks
        return lk.encode_motion_reply(
            cmd,
            round(m.temperature),
            round(m.current / self.scale.reply_amps),
            round(m.rotor_velocity * _DEG),
            encoder,
        )

    def _periodic(self, now_ns: int) -> list[Frame]:
        return []  # it speaks only when asked

    def _status(self, cmd: lk.Command) -> bytes:
        current = self.model.electrical_power / max(self.supply_voltage, 1.0)
        return lk.encode_status_1(cmd, round(self.model.temperature), self.supply_voltage,
                                  current, motor_on=self.on, error=self.error)
