"""PowerLimitStage: a group of joints whose efforts share one power limit, at the loop rate.

A component of the loop that modifies the efforts (so it runs after every actuator's
update, before packing; rm_base.loop.order): it predicts
the group's electrical power from the efforts the actuators' own loops just computed and
the speeds measured at most a tick ago (:func:`rm_base.control.limit_power`), and when the
prediction is over the limit scales every effort of the group by one common factor, as
RoboMaster firmware does after its wheel speed loops (one factor keeps the direction of the
chassis' force and turn). The limit is set by whoever knows it (the chassis plugin, from
/chassis_cmd or the referee) with :attr:`PowerLimitStage.limit_w`; a plain float, so
setting it from another thread needs no lock.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from rm_base.control import ChassisPowerModel, PowerLimitResult, limit_power
from rm_base.hardware.actuators import Actuator
from rm_base.hardware.supercap import PowerSupply, Supercap
from rm_base.loop.data import JOINT_EFFORTS, JOINT_STATES


class PowerLimitStage:
    """One power limit over a group of actuators (see the module docstring).

    Args:
        name: group name (the stage is ``power limit <name>`` in the loop's timing).
        actuators: the group, in the order the model's speeds and efforts are given.
        model: the group's power model.

    Attributes:
        limit_w: allowed power [W], >= 0; inf (the default) limits nothing.
        last: what the last tick did (scale, efforts, predicted power), None before it.
        supply: the referee's limit and buffer and a commanded limit, for the
            super-capacitor (set by the plugin, as ``limit_w``).
        supercap: the super-capacitor that feeds the group, or None; with one, the limit
            of a tick is what it allows from ``limit_w`` and ``supply``
            (rm_base.hardware.supercap).
    """

    def __init__(
        self, name: str, actuators: Sequence[Actuator], model: ChassisPowerModel
    ) -> None:
        self.name = f'power limit {name}'
        # modifies the efforts: after the actuators' update, before pack
        self.reads = (JOINT_EFFORTS, JOINT_STATES)
        self.writes = (JOINT_EFFORTS,)
        self.group = name
        self.model = model
        self.limit_w = math.inf
        self.last: PowerLimitResult | None = None
        self.supply = PowerSupply()
        self.supercap: Supercap | None = None
        self._actuators = tuple(actuators)

    @property
    def joints(self) -> tuple[str, ...]:
        """The group's joint names, in order."""
        return tuple(a.name for a in self._actuators)

    def __call__(self, now_ns: int, dt: float) -> bool:
        """Scale this tick's efforts of the group if they would draw too much."""
        supercap = self.supercap
        limit_w = self.limit_w
        if supercap is not None:  # every tick, also with no effort: it keeps its state
            limit_w = supercap.allow(limit_w, self.supply, now_ns)
        actuators = self._actuators
        efforts = [a.effort_out for a in actuators]
        if not any(efforts):
            self.last = None
            return False
        speeds = [fb.velocity if (fb := a.feedback) is not None else 0.0 for a in actuators]
        result = limit_power(self.model, efforts, speeds, limit_w)
        if result.scale < 1.0:
            for actuator in actuators:
                actuator.scale_output(result.scale)
        self.last = result
        return True
