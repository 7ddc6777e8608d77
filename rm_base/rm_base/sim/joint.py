"""A simulated joint: a motor's output seen through a direction and a zero."""

from __future__ import annotations

from dataclasses import dataclass

from rm_base.sim_devices.device import SimDevice


@dataclass(frozen=True)
class Joint:
    """A joint driven by one motor (gimbal yaw and pitch, the trigger, a friction wheel).

    Attributes:
        device: the motor.
        direction: +1 or -1, joint angle sign relative to the motor's output angle.
        zero: motor output angle at which the joint reads 0 [rad].
    """

    device: SimDevice
    direction: float = 1.0
    zero: float = 0.0

    @property
    def angle(self) -> float:
        """Joint angle [rad]."""
        return self.direction * (self.device.model.angle - self.zero)

    @property
    def velocity(self) -> float:
        """Joint velocity [rad/s]."""
        return self.direction * self.device.model.velocity
