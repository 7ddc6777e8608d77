"""Simulated motor running the MIT Cheetah firmware (Ben Katz).

Like a Damiao but with its own reply (6 or 7 bytes to the master id, no error nibble, no
temperature) and no clear-error frame.
"""

from __future__ import annotations

from rm_base.hardware.protocols import mit
from rm_base.motors.cheetah import protocol as cheetah
from rm_base.sim_devices.device import Frame
from rm_base.sim_devices.mit_device import MitDevice
from rm_base.sim_devices.motor import DriveMode, MotorModel
from rm_base.sim_devices.motor_params import MotorType


class CheetahDevice(MitDevice):
    """A motor running Ben Katz's MIT Cheetah firmware.

    Attributes:
        reply_voltage: send the 7-byte reply with bus voltage (STM32 firmware) instead of
            the 6-byte one (mbed firmware).
    """

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
