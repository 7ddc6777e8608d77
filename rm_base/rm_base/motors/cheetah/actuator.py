"""Motors running the MIT Cheetah firmware, on the MIT actuator base."""

from __future__ import annotations

import math

import can

from rm_base.hardware.actuators.base import Defaults
from rm_base.hardware.actuators.mit import MitActuator, limits_from_config
from rm_base.hardware.config import JointConfig, SafetyConfig
from rm_base.hardware.protocols.mit import SystemCommand
from rm_base.motors.cheetah import protocol as cheetah


class Cheetah(MitActuator):
    """A motor running Ben Katz's MIT Cheetah firmware (no temperatures, no clear-error)."""

    type_name = 'cheetah'
    max_motor_id = 0xFF  # the reply carries the id in one byte

    def __init__(self, config: JointConfig, safety: SafetyConfig | None = None) -> None:
        """Build the actuator; see the module docstring for the options.

        Raises:
            HardwareConfigError: invalid id or option.
        """
        limits = limits_from_config(
            config.name, cheetah.CHEETAH_DEFAULT_LIMITS, self.read_options(config)['limits']
        )
        self.defaults = Defaults(1.0, None, limits.t_max, limits.v_max, math.inf)
        super().__init__(config, limits, safety)

    def _match(self, msg: can.Message) -> bool:
        data = msg.data
        return len(data) > 0 and data[0] == self.motor_id

    def _decode(self, msg: can.Message) -> tuple[float, float, float, float | None, int]:
        reply = cheetah.decode_reply(msg.data, self.limits)
        position = self._position_unwrapper.update(reply.position)
        return position, reply.velocity, reply.torque, None, 0

    def _system_data(self, command: SystemCommand) -> bytes:
        return cheetah.cheetah_system_frame(command)
