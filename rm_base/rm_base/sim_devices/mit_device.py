"""The base of simulated MIT-protocol motors (the Damiao and Cheetah families' devices).

Such a motor runs the MIT law ``kp·(p − q) + kd·(v − dq) + τ`` itself, replies to each
command on its master id, and takes enable / disable / set-zero system frames.
"""

from __future__ import annotations

from abc import abstractmethod

from rm_base.hardware.protocols import mit
from rm_base.sim_devices.device import Frame, SimDevice
from rm_base.sim_devices.motor import MotorModel
from rm_base.sim_devices.motor_params import MotorType


class MitDevice(SimDevice):
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
