"""Simulated DJI ESCs (C620 + M3508, C610 + M2006, GM6020) on a CAN bus.

A DJI device takes its slot of a group command frame (0x200/0x1FF/0x2FF/0x1FE/0x2FE),
sends a feedback frame at a fixed rate (default 1 kHz) whether commanded or not, and drops
to zero current when no command came for ``command_timeout`` (default 100 ms; the real
C620's value is not documented).
"""

from __future__ import annotations

from rm_base.motors.dji import protocol as dji
from rm_base.sim_devices.device import NS_PER_S, Frame, SimDevice
from rm_base.sim_devices.motor import MotorModel
from rm_base.sim_devices.motor_params import MotorType
from rm_base.sim_devices.schedule import RateSchedule


class DjiDevice(SimDevice):
    """A DJI motor with its ESC: C620 + M3508, C610 + M2006, or GM6020 (voltage/current).

    Attributes:
        spec: ids, limits and scales (from :func:`rm_base.motors.dji.protocol.make_dji_spec`).
        command_timeout_ns: no command for this long -> zero current; None never.
        command_raw: the last raw value taken from the motor's slot.
    """

    shares_command_frames = True

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
            None if not command_timeout else round(command_timeout * NS_PER_S)
        )
        self.command_raw = 0
        self._voltage_control = spec.command_unit == 'V'
        self._last_command_ns: int | None = None
        self._timed_out = True
        self._feedback = RateSchedule(
            feedback_rate_hz, first_ns=round(NS_PER_S / feedback_rate_hz)
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
