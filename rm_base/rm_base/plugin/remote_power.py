"""A plugin's power stage run by the CAN bridge in another process (the split layout).

rm_robot asks the bridge for the stage on /power_limit (latched), and the bridge runs it in
its own 1 kHz loop after the wheels' speed loops (docs/ARCHITECTURE.md, "Two ways to run").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from rm_base.control import ChassisPowerModel, PowerLimitResult, estimate_power
from rm_base.errors import InputRejectedError
from rm_base.hardware.supercap import PowerSupply
from rm_base.plugin.joints import JointStateView
from rm_msgs.msg import PowerLimit

POWER_LIMIT_TOPIC = 'power_limit'
"""Power limits the CAN bridge runs for rm_robot in another process (rm_msgs/PowerLimit)."""

#: Latched, one message per group kept: a bridge that starts later gets every stage.
POWER_LIMIT_QOS = QoSProfile(
    depth=16, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


class RemotePowerStage:
    """A plugin's power stage run by the bridge in another process (see POWER_LIMIT_TOPIC).

    Behaves as the loop's own stage does for the plugin: set ``limit_w``; ``last`` tells
    the efforts and the power, here from the latest joint states (what the bridge applied).
    A limit goes out when it changes (latched, so a bridge started later gets it too).
    """

    def __init__(
        self, publisher: Any, group: str, joints: Sequence[str], model: ChassisPowerModel,
        joint_states: JointStateView,
    ) -> None:
        self._publisher = publisher
        self._group = group
        self._joints = tuple(joints)
        self._model = model
        self._joint_states = joint_states
        self._limit_w = math.inf
        self._supply = PowerSupply()
        self._publish()

    def _publish(self) -> None:
        """The request as it stands now (latched: a bridge started later gets it too)."""
        model = self._model
        self._publisher.publish(PowerLimit(
            group=self._group, joints=list(self._joints), k1=model.k1, k2=model.k2,
            static_power_w=model.static_power_w, limit_w=self._limit_w,
            referee_limit_w=self._supply.referee_limit_w, buffer_j=self._supply.buffer_j,
            request_w=self._supply.request_w,
        ))

    @property
    def model(self) -> ChassisPowerModel:
        """The group's power model; a new one goes out to the bridge."""
        return self._model

    @model.setter
    def model(self, model: ChassisPowerModel) -> None:
        self._model = model
        self._publish()

    @property
    def limit_w(self) -> float:
        """The allowed power [W] (inf: no limit)."""
        return self._limit_w

    @limit_w.setter
    def limit_w(self, value: float) -> None:
        if value != self._limit_w:
            self._limit_w = float(value)
            self._publish()

    @property
    def supply(self) -> PowerSupply:
        """The referee's numbers for a super-capacitor; new ones go out to the bridge."""
        return self._supply

    @supply.setter
    def supply(self, value: PowerSupply) -> None:
        if value != self._supply:
            self._supply = value
            self._publish()

    @property
    def last(self) -> PowerLimitResult | None:
        """The efforts the bridge applied and their predicted power; None before states."""
        states = self._joint_states.snapshot(self._joints)
        if len(states) != len(self._joints):
            return None
        torques = [states[j].effort for j in self._joints]
        speeds = [states[j].velocity for j in self._joints]
        try:
            power = estimate_power(self._model, torques, speeds)
        except InputRejectedError:  # a joint offline reports NaN
            return None
        return PowerLimitResult(math.nan, tuple(torques), math.nan, power)
