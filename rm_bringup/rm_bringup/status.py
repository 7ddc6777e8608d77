"""A compact live status line of the robot, built from its ROS topics.

``StatusView`` subscribes to the mechanism states, /odom, the referee's robot status,
/actuator_states and /diagnostics and keeps the latest of each; ``format_status`` turns
them into one line such as::

    chassis GYRO v(0.98,0.00,5.97) | pose 1.20 -0.31 87deg | wheels 19.1 -3.2 3.2 -19.1
    | gimbal RATE y 0.12 p -0.05 | shooter READY 5 shots | hp 200/200 | can0 31% can1 18%
    | overruns 0/s | cmd external | offline -

It reads topics only, so the same view works whether the nodes run in this process (the
bringup runner) or elsewhere.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Mapping
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from rm_base.plugin.command_status import NEW_KEY as REFUSED_NOW
from rm_base.plugin.command_status import STATUS_NAME as COMMANDS_STATUS

from rm_msgs.msg import (
    ActuatorState,
    ChassisCmd,
    ChassisState,
    GimbalCmd,
    GimbalState,
    RefereeRobotStatus,
)
from rm_msgs.msg import ShooterState as ShooterStateMsg

_CHASSIS_NAMES = {
    ChassisCmd.PASSIVE: 'PASSIVE',
    ChassisCmd.RAW: 'RAW',
    ChassisCmd.FOLLOW: 'FOLLOW',
    ChassisCmd.TWIST: 'TWIST',
    ChassisCmd.GYRO: 'GYRO',
    ChassisCmd.POSITION: 'POSITION',
}
_GIMBAL_NAMES = {GimbalCmd.PASSIVE: 'PASSIVE', GimbalCmd.RATE: 'RATE', GimbalCmd.TRACK: 'TRACK'}
_SHOOTER_NAMES = {
    ShooterStateMsg.PASSIVE: 'PASSIVE',
    ShooterStateMsg.FEED: 'FEED',
    ShooterStateMsg.READY: 'READY',
    ShooterStateMsg.PUSH: 'PUSH',
    ShooterStateMsg.BLOCK: 'BLOCK',
}


def _diag_values(status: Any) -> dict[str, str]:
    return {kv.key: kv.value for kv in status.values}


def format_status(latest: Mapping[str, Any]) -> str:
    """One status line from the latest messages; a missing source is left out.

    Args:
        latest: the latest message per source: ``chassis`` (ChassisState), ``gimbal``,
            ``odom`` (Odometry), ``shooter``, ``referee`` (RefereeRobotStatus),
            ``actuators`` (ActuatorState) and ``diagnostics`` (status name ->
            DiagnosticStatus); ``refused``: the command topics a plugin refused a
            moment ago, comma-separated.
    """
    parts = []
    chassis = latest.get('chassis')
    if chassis is not None:
        v = chassis.measured_vel
        parts.append(
            f'chassis {_CHASSIS_NAMES.get(chassis.state, chassis.state)} '
            f'v({v.linear.x:.2f},{v.linear.y:.2f},{v.angular.z:.2f})'
        )
        odom = latest.get('odom')
        if odom is not None:
            parts.append(_pose_part(odom.pose.pose))
        if len(chassis.wheel_speed):
            parts.append('wheels ' + ' '.join(f'{w:.1f}' for w in chassis.wheel_speed))
    gimbal = latest.get('gimbal')
    if gimbal is not None:
        parts.append(
            f'gimbal {_GIMBAL_NAMES.get(gimbal.state, gimbal.state)} '
            f'y {gimbal.yaw:.2f} p {gimbal.pitch:.2f}'
        )
    shooter = latest.get('shooter')
    if shooter is not None:
        fault = ' FAULT' if shooter.fault else ''
        parts.append(
            f'shooter {_SHOOTER_NAMES.get(shooter.state, shooter.state)} '
            f'{shooter.shots_fired} shots{fault}'
        )
    referee = latest.get('referee')
    if referee is not None:
        parts.append(_referee_part(referee))
    diagnostics = latest.get('diagnostics')
    if diagnostics:
        loads, overruns, charge, cap, slipped = [], None, {}, None, 0.0
        for status in diagnostics.values():
            values = _diag_values(status)
            kind = status.name.split(': ', 1)[-1]  # 'can_bridge: bus can0' -> 'bus can0'
            if kind.startswith('bus '):
                load = values.get('load [%]', '')
                name = kind.removeprefix('bus ')
                try:
                    loads.append(f'{name} {float(load):.0f}%')
                except ValueError:
                    loads.append(f'{name} ?')
            elif kind == 'scheduler':
                overruns = values.get('overruns')
            elif kind == 'supercap':
                cap = _supercap_part(values)
            elif kind == 'simulator':
                try:  # another node's report: a value that is no number says nothing
                    slipped = float(values.get('slipped [s]', 0.0))
                except ValueError:
                    slipped = 0.0
            elif kind == 'command sources':
                charge = {k.removesuffix(' in charge'): v or '-' for k, v in values.items()
                          if k.endswith(' in charge')}
        if cap is not None:
            parts.append(cap)
        if loads:
            parts.append(' '.join(sorted(loads)))
        rate = latest.get('overrun_rate')
        if rate is not None:  # a rate tells now; a running total only that it once was
            parts.append(f'overruns {rate:.0f}/s')
        elif overruns is not None:
            parts.append(f'overruns {overruns}')
        if slipped > 0.0:  # a starved simulator: its robot moves slower than the clock says
            parts.append(f'sim slipped {slipped:.1f} s')
        if charge:  # who commands: one name when one source has every topic
            names = set(charge.values())
            parts.append('cmd ' + (names.pop() if len(names) == 1 else ' '.join(
                f'{topic.lstrip("/").removesuffix("_cmd")}:{name}'
                for topic, name in sorted(charge.items()))))
    refused = latest.get('refused', '')
    if refused:  # commands a plugin refused a moment ago: the log says why
        parts.append('refused ' + ' '.join(
            t.lstrip('/').removesuffix('_cmd') for t in refused.split(',')))
    actuators = latest.get('actuators')
    if actuators is not None:
        offline = [n for n, ok in zip(actuators.name, actuators.online, strict=False) if not ok]
        hot = [
            f'{n} {t:.0f}C'
            for n, t in zip(actuators.name, actuators.temperature, strict=False)
            if not math.isnan(t) and t >= 70.0
        ]
        parts.append('offline ' + (','.join(offline) if offline else '-'))
        if hot:
            parts.append('hot ' + ','.join(hot))
    return ' | '.join(parts) if parts else 'waiting for the robot...'


def _supercap_part(values: Mapping[str, str]) -> str:
    """``cap 73% burst``: how full the capacitor is and what it does; ``cap offline``."""
    state = values.get('state', '?')
    try:
        energy = float(values.get('energy [%]', 'nan'))
    except ValueError:
        energy = math.nan
    return f'cap {energy:.0f}% {state}' if math.isfinite(energy) else f'cap {state}'


def _pose_part(pose: Any) -> str:
    """``pose 1.00 0.50 90deg``: odom -> base_link, x and y [m] and the heading."""
    q = pose.orientation
    yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    return f'pose {pose.position.x:.2f} {pose.position.y:.2f} {math.degrees(yaw):.0f}deg'


def _referee_part(status: Any) -> str:
    """``hp 300/300``, and what the referee switched off: ``DESTROYED``, ``power off chassis``."""
    text = f'hp {status.hp}/{status.max_hp}'
    if status.hp == 0:
        return text + ' DESTROYED'
    off = [name for name, on in (('gimbal', status.gimbal_power), ('chassis', status.chassis_power),
                                 ('shooter', status.shooter_power)) if not on]
    return text + (' power off ' + ','.join(off) if off else '')


#: How long the line names the topics of a refused command [s]: two of bringup's lines.
REFUSED_HOLD_S = 4.0


#: What a narrow terminal leaves out first: the wheels' speeds, news of nothing (no
#: overrun, nothing offline), the bus loads, then who commands.
_DROP_FIRST = (
    lambda p: p.startswith('wheels '),
    lambda p: p.startswith('pose '),
    lambda p: p in ('overruns 0/s', 'offline -'),
    lambda p: p.startswith('can'),
    lambda p: p.startswith('cmd '),
)


def fit_status(line: str, width: int) -> str:
    """Line in width columns: the parts of least use dropped first, then cut."""
    parts = line.split(' | ')
    for unneeded in _DROP_FIRST:
        if len(' | '.join(parts)) <= width:
            break
        parts = [p for p in parts if not unneeded(p)]
    fitted = ' | '.join(parts)
    return fitted if len(fitted) <= width else fitted[: max(width - 1, 0)] + '>'


class StatusView:
    """Keeps the latest robot states from topics, for :func:`format_status`.

    Args:
        node: node to create the subscriptions on (callbacks run on its executor).
        clock: monotonic time [s] (tests pass their own).
    """

    def __init__(self, node: Node, clock: Callable[[], float] = time.monotonic) -> None:
        self._lock = threading.Lock()
        self._clock = clock
        self._latest: dict[str, Any] = {'diagnostics': {}}
        self._refused: tuple[str, float] | None = None  # (topics, when seen [s])
        self._last_overruns: tuple[int, float] | None = None  # (total, stamp [s])
        qos = qos_profile_sensor_data
        node.create_subscription(ChassisState, '/chassis_state', self._keep('chassis'), qos)
        node.create_subscription(GimbalState, '/gimbal_state', self._keep('gimbal'), qos)
        node.create_subscription(ShooterStateMsg, '/shooter_state', self._keep('shooter'), qos)
        node.create_subscription(ActuatorState, 'actuator_states', self._keep('actuators'), qos)
        node.create_subscription(Odometry, '/odom', self._keep('odom'), qos)
        node.create_subscription(
            RefereeRobotStatus, '/referee/robot_status', self._keep('referee'), 10
        )
        node.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)

    def _keep(self, key: str):
        def store(msg: Any) -> None:
            with self._lock:
                self._latest[key] = msg

        return store

    def _on_diagnostics(self, msg: DiagnosticArray) -> None:
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        with self._lock:
            for status in msg.status:
                self._latest['diagnostics'][status.name] = status
                if status.name.endswith(': scheduler'):
                    self._note_overruns(status, stamp)
                elif status.name.endswith(f': {COMMANDS_STATUS}'):
                    self._note_refused(status)

    def _note_refused(self, status: Any) -> None:
        # one report a second says it; the line may be drawn just before and after that
        topics = _diag_values(status).get(REFUSED_NOW, '')
        if topics:
            self._refused = (topics, self._clock())

    def _note_overruns(self, status: Any, stamp: float) -> None:
        try:
            total = int(_diag_values(status)['overruns'])
        except (KeyError, ValueError):
            return
        last = self._last_overruns
        if last is not None and stamp > last[1]:
            self._latest['overrun_rate'] = max(0, total - last[0]) / (stamp - last[1])
        self._last_overruns = (total, stamp)

    def line(self) -> str:
        """The current status line."""
        with self._lock:
            latest = dict(self._latest)
            latest['diagnostics'] = dict(latest['diagnostics'])
            refused = self._refused
        if refused is not None and self._clock() - refused[1] < REFUSED_HOLD_S:
            latest['refused'] = refused[0]
        return format_status(latest)
