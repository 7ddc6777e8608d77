"""ClientUi: the operator's client UI, drawn through the referee link.

It listens to the robot (/chassis_state, /shooter_state, the referee's reports, the
super-capacitor's /diagnostics status), lays out what the operator needs
(``rm_plugins.ui.layout``) and sends the client only what changed (``rm_plugins.ui.sync``):
at most one 0x0301 frame a run, on referee/interaction, which the referee plugin sends on
its link within the rules' limits. Run it below the referee plugin's
``interaction.max_hz`` (8 Hz against 10 by default) so that its frames never wait there.
"""

from __future__ import annotations

import math
import threading
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.time import Time
from rm_base.plugin import DefaultState, PluginBase

from rm_msgs.msg import (
    ChassisCmd,
    ChassisState,
    RefereeGameStatus,
    RefereeInteraction,
    RefereePowerHeat,
    RefereeRobotStatus,
    ShooterState,
)
from rm_plugins.ui.layout import UiInputs, layout
from rm_plugins.ui.sync import UiSync

_CHASSIS_NAMES = {v: k for k, v in vars(ChassisCmd).items() if k.isupper() and
                  not k.startswith('GEAR_') and isinstance(v, int)}
_GEAR_NAMES = {v: k.removeprefix('GEAR_') for k, v in vars(ChassisCmd).items()
               if k.startswith('GEAR_') and isinstance(v, int)}
_SHOOTER_NAMES = {v: k for k, v in vars(ShooterState).items() if k.isupper()
                  and isinstance(v, int)}
_HERO = 1  # robot id (red; blue + 100): the hero's barrel is the 42 mm one


class ClientUi(PluginBase):
    """The operator's client UI (see the module docstring).

    Parameters (under ``<name>.``): ``aim_x``, ``aim_y`` (the aim point on the client's
    screen [px]), ``refresh_s`` (re-add everything this often, for a client that
    restarted).

    States: PASSIVE (disabled), ACTIVE (drawing). The client is cleared and drawn anew
    when the game's stage changes and when the robot comes back to life (the moments a
    client is known to reconnect), and redrawn every ``refresh_s``.
    """

    def on_init(self) -> None:
        """Read the parameters; subscribe to what the client shows."""
        p = self.params
        self._aim = (
            p.integer('aim_x', 960, ge=0, le=1919,
                      description='the aim point on the client screen, from the left [px]'),
            p.integer('aim_y', 540, ge=0, le=1079,
                      description='the aim point on the client screen, from the bottom [px]'),
        )
        self._sync = UiSync(p.double(
            'refresh_s', 5.0, unit='s', gt=0.0,
            description='re-add every figure this often (a restarted client shows none)'))
        self._lock = threading.Lock()
        self._heard: dict[str, Any] = {}
        self._resend = False
        self._progress: int | None = None
        self._alive: bool | None = None
        self._out = self.create_publisher(RefereeInteraction, 'referee/interaction', 10)
        for topic, msg_type, key in (
            ('/chassis_state', ChassisState, 'chassis'), ('/shooter_state', ShooterState,
                                                          'shooter'),
            ('referee/power_heat', RefereePowerHeat, 'heat'),
        ):
            self.subscribe(topic, msg_type, self._keeper(key))
        self.subscribe('referee/robot_status', RefereeRobotStatus, self._on_robot_status, 10)
        self.subscribe('referee/game_status', RefereeGameStatus, self._on_game_status, 10)
        self.subscribe('/diagnostics', DiagnosticArray, self._on_diagnostics, 10)

    def on_enable(self) -> None:
        """Draw from scratch (the client may show an earlier run's figures)."""
        self._sync.resend()

    def update(self, now: Time, dt: float) -> None:
        """Send the next change, if any."""
        self.transition(DefaultState.ACTIVE, 'drawing')
        with self._lock:
            heard, resend, self._resend = dict(self._heard), self._resend, False
        if resend:
            self._sync.resend()
        frame = self._sync.next_frame(layout(self._layout_inputs(heard)), now.nanoseconds)
        if frame is not None:
            self._out.publish(RefereeInteraction(content_id=frame[0], content=frame[1]))

    # -- what it hears (the delivering thread) ----------------------------------------------

    def _keeper(self, key: str) -> Any:
        def keep(msg: Any, receive_ns: int) -> None:
            with self._lock:
                self._heard[key] = msg
        return keep

    def _on_robot_status(self, msg: RefereeRobotStatus, receive_ns: int) -> None:
        alive = msg.hp > 0
        with self._lock:
            self._heard['robot'] = msg
            if self._alive is False and alive:
                self._resend = True  # back to life: its client reconnects
            self._alive = alive

    def _on_game_status(self, msg: RefereeGameStatus, receive_ns: int) -> None:
        with self._lock:
            if self._progress is not None and msg.progress != self._progress:
                self._resend = True  # a new stage: clients (re)connect
            self._progress = msg.progress

    def _on_diagnostics(self, msg: DiagnosticArray, receive_ns: int) -> None:
        for status in msg.status:
            if status.name.endswith(': supercap'):
                values = {kv.key: kv.value for kv in status.values}
                with self._lock:
                    self._heard['cap'] = values

    # -- the layout's inputs -----------------------------------------------------------------

    def _layout_inputs(self, heard: dict[str, Any]) -> UiInputs:
        chassis, shooter = heard.get('chassis'), heard.get('shooter')
        robot, heat_msg, cap = heard.get('robot'), heard.get('heat'), heard.get('cap')
        heat = limit = None
        if robot is not None and heat_msg is not None:
            hero = robot.robot_id % 100 == _HERO
            heat = float(heat_msg.heat_42mm if hero else heat_msg.heat_17mm)
            limit = float(robot.barrel_heat_limit)
            if not (math.isfinite(heat) and math.isfinite(limit)):
                heat = limit = None
        energy = None
        if cap is not None:
            try:
                energy = float(cap.get('energy [%]', 'nan')) / 100.0
            except ValueError:
                energy = None
            if energy is not None and not math.isfinite(energy):
                energy = None
        return UiInputs(
            chassis=_CHASSIS_NAMES.get(chassis.state) if chassis is not None else None,
            gear=_GEAR_NAMES.get(chassis.speed_gear) if chassis is not None else None,
            power_limit_w=(float(chassis.power_limit) if chassis is not None
                           and math.isfinite(chassis.power_limit) else None),
            shooter=_SHOOTER_NAMES.get(shooter.state) if shooter is not None else None,
            friction_ready=bool(shooter.friction_ready) if shooter is not None else False,
            cap_energy=energy,
            cap_state=cap.get('state') if cap is not None else None,
            heat=heat,
            heat_limit=limit,
            aim=self._aim,
        )
