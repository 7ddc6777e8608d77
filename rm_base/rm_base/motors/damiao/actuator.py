"""Damiao DM motors in MIT mode (register CTRL_MODE = 1) on the MIT actuator base.

Options beyond the MIT ones (rm_base/hardware/actuators/mit.py): ``model``, a key of
:data:`rm_base.motors.damiao.protocol.DM_MODEL_LIMITS` (required for type ``damiao``,
implied by ``dm4310``...).
"""

from __future__ import annotations

from typing import ClassVar

import can

from rm_base.config.schema import Schema, string
from rm_base.hardware.actuators.base import Defaults
from rm_base.hardware.actuators.mit import MitActuator, limits_from_config
from rm_base.hardware.config import JointConfig, SafetyConfig
from rm_base.hardware.errors import HardwareConfigError
from rm_base.motors.damiao import protocol as damiao


class Damiao(MitActuator):
    """A Damiao motor in MIT mode (register CTRL_MODE = 1)."""

    type_name = 'damiao'
    default_model: ClassVar[str | None] = None
    options_schema = Schema((
        *MitActuator.options_schema.keys,
        string('model', None, nonempty=True,
               description='DM4310, DM8009...: its MIT ranges; type damiao must set it'),
    ))

    def __init__(self, config: JointConfig, safety: SafetyConfig | None = None) -> None:
        """Build the actuator; see the module docstring for the options.

        Raises:
            HardwareConfigError: unknown model, invalid id or option.
        """
        options = self.read_options(config)
        model = options['model'] or self.default_model
        if model is None:
            raise HardwareConfigError(
                f'joints.{config.name}.model is required for type {self.type_name!r} '
                f'(one of {", ".join(damiao.DM_MODEL_LIMITS)})'
            )
        try:
            base = damiao.dm_limits(model)
        except HardwareConfigError as err:
            raise HardwareConfigError(f'joints.{config.name}.model: {err}') from err
        limits = limits_from_config(config.name, base, options['limits'])
        # the motor reports its own output shaft; torque is reported, so no Kt is needed
        self.defaults = Defaults(1.0, None, limits.t_max, limits.v_max, 80.0)
        self.model = model.upper()
        self._device_state: int = damiao.DmState.DISABLED  # or an unknown code
        super().__init__(config, limits, safety)

    @staticmethod
    def _default_master_id(motor_id: int) -> int:
        return min(motor_id + 0x10, 0x7FF)

    def reply_key(self) -> str:
        """Damiao motors reply on their master id with the low nibble of their id."""
        return f'master id 0x{self.master_id:03X} and id nibble {self.motor_id & 0x0F}'


    def _match(self, msg: can.Message) -> bool:
        data = msg.data
        return len(data) > 0 and (data[0] & 0x0F) == (self.motor_id & 0x0F)

    def _decode(self, msg: can.Message) -> tuple[float, float, float, float | None, int]:
        fb = damiao.decode_feedback(msg.data, self.limits)
        self._device_state = fb.state
        position = self._position_unwrapper.update(fb.position)
        error = int(fb.state) if fb.state in damiao.FAULT_STATES else 0
        return position, fb.velocity, fb.torque, float(max(fb.t_mos, fb.t_rotor)), error

    def _reports_disabled(self) -> bool:
        return self._device_state == damiao.DmState.DISABLED


class Dm4310(Damiao):
    """DM4310 (24 V): P ±12.5 rad, V ±30 rad/s, T ±10 N·m."""

    type_name = 'dm4310'
    default_model = 'DM4310'


class Dm4340(Damiao):
    """DM4340: ranges conflict between DM's SDKs — set ``limits`` from the motor."""

    type_name = 'dm4340'
    default_model = 'DM4340'


class Dm8009(Damiao):
    """DM8009: P ±12.5 rad, V ±45 rad/s, T ±54 N·m."""

    type_name = 'dm8009'
    default_model = 'DM8009'


class Dm10010L(Damiao):
    """DM10010L: P ±12.5 rad, V ±25 rad/s, T ±200 N·m."""

    type_name = 'dm10010l'
    default_model = 'DM10010L'
