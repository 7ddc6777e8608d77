"""AutoAim: aim the gimbal at the vision stack's target, and fire when the barrel is on it.

docs/AUTO_AIM.md. Inputs: ``/tracker/target`` (auto_aim_interfaces/Target, best effort as
the tracker publishes it), ``/odom`` (where the gimbal is), ``/gimbal_state`` (the barrel
against its aim) and ``/shooter_state`` (the friction wheels, the bullet speed). Outputs:
``/gimbal_cmd`` TRACK at the predicted plate (or centre), and with ``auto_fire``
``/shoot_cmd``: READY while tracking, PUSH (continuous, at ``fire_hz``) while the barrel
is on the plate. The muzzle speed for the ballistics is the referee's measured one
(``referee/shot``, the mean of the last few), else the shooter's commanded speed.
"""

from __future__ import annotations

import collections
import enum
import math

from auto_aim_interfaces.msg import Target
from nav_msgs.msg import Odometry
from rclpy.qos import qos_profile_sensor_data
from rclpy.time import Time
from rm_base.errors import InputRejectedError
from rm_base.geometry import wrap_to_pi
from rm_base.geometry.armor_target import ArmorTarget
from rm_base.geometry.ballistics import ProjectileModel
from rm_base.plugin import LatestMessage, PluginBase

from rm_msgs.msg import GimbalCmd, GimbalState, RefereeShot, ShootCmd, ShooterState
from rm_plugins.autoaim.solver import AimPoint, AimSettings, aim_point

_NS_PER_S = 1_000_000_000
_SPEEDS_KEPT = 5  # measured shots averaged for the muzzle speed


class AimState(enum.IntEnum):
    """PASSIVE: disabled or no target; TRACKING: on a plate; CENTRE: spin too fast."""

    PASSIVE = 0
    TRACKING = 1
    CENTRE = 2


class AutoAim(PluginBase):
    """Aim and fire at rm_auto_aim's target (see the module docstring).

    Parameters (under ``<name>.``): ``latency``, ``lead``, ``max_v_yaw``,
    ``target_timeout``, ``pivot_height``, ``barrel_length``, ``bullet_drag``,
    ``bullet_speed`` (when the shooter reports none), ``auto_fire``, ``fire_hz``,
    ``fire_tolerance``, ``plate_half_width``, ``plate_half_height``.
    """

    State = AimState

    def on_init(self) -> None:
        """Read the parameters; subscribe; create the command publishers."""
        p = self.params
        self._settings = AimSettings(
            latency_s=p.double('latency', 0.05, unit='s', ge=0.0, le=1.0,
                               description='from now until the barrel acts on a command'),
            lead=p.double('lead', math.radians(15.0), unit='rad', ge=0.0, le=math.pi / 4,
                          description='the plate choice leans this far toward the plate '
                          'coming into view'),
            max_v_yaw=p.double('max_v_yaw', 6.0, unit='rad/s', gt=0.0,
                               description='a faster spin is aimed at its centre'),
            model=ProjectileModel(
                drag=p.double('bullet_drag', 0.02, unit='1/m', ge=0.0,
                              description="the projectile's drag (the gimbal's)")),
            barrel_length=p.double('barrel_length', 0.15, unit='m', ge=0.0,
                                   description="pitch axis to muzzle (the gimbal's)"),
        )
        self._timeout_ns = round(p.double(
            'target_timeout', 0.2, unit='s', gt=0.0,
            description='an older target is no target') * _NS_PER_S)
        self._pivot_height = p.double('pivot_height', 0.35, unit='m',
                                      description="the gimbal's axes above the odom origin")
        self._default_speed = p.double(
            'bullet_speed', 15.0, unit='m/s', gt=0.0,
            description='the speed the shooter is commanded (with auto_fire), and the one '
            'aimed with until the referee has measured shots')
        self._auto_fire = p.boolean('auto_fire', False,
                                    description='fire when the barrel is on the plate')
        self._fire_period_ns = round(_NS_PER_S / p.double(
            'fire_hz', 8.0, unit='Hz', gt=0.0, description='most shots a second'))
        self._tolerance = p.double(
            'fire_tolerance', 0.6, gt=0.0, le=1.0,
            description="fire while within this share of a plate's half size of the aim")
        self._half = (
            p.double('plate_half_width', 0.0675, unit='m', gt=0.0,
                     description="half a plate's width (small: 135 mm)"),
            p.double('plate_half_height', 0.0625, unit='m', gt=0.0,
                     description="half a plate's height"),
        )
        self._target = LatestMessage(use_stamp=True)
        self._odom = LatestMessage(use_stamp=False)
        self._gimbal = LatestMessage(use_stamp=False)
        self._shooter = LatestMessage(use_stamp=False)
        self.subscribe('/tracker/target', Target, self._target.put, qos_profile_sensor_data)
        self.subscribe('/odom', Odometry, self._odom.put, qos_profile_sensor_data)
        self.subscribe('/gimbal_state', GimbalState, self._gimbal.put)
        self.subscribe('/shooter_state', ShooterState, self._shooter.put)
        self._speeds: collections.deque[float] = collections.deque(maxlen=_SPEEDS_KEPT)
        self.subscribe('referee/shot', RefereeShot, self._on_shot, 10)
        self._gimbal_out = self.create_publisher(GimbalCmd, '/gimbal_cmd', 10)
        self._shoot_out = self.create_publisher(ShootCmd, '/shoot_cmd', 10)
        self._burst = 0
        self._firing = False
        self._distance: float | None = None

    def update(self, now: Time, dt: float) -> None:
        """Aim at the target (if fresh); fire when on it."""
        now_ns = now.nanoseconds
        aim = self._aim(now_ns)
        if aim is None:
            return
        target_msg, speed, found = aim
        self.transition(AimState.TRACKING if found.plate is not None else AimState.CENTRE,
                        f'plate {found.plate}' if found.plate is not None else
                        'spin too fast: the centre')
        cmd = GimbalCmd(mode=GimbalCmd.TRACK, bullet_speed=speed)
        cmd.header.stamp = now.to_msg()
        cmd.target.header.frame_id = target_msg.header.frame_id
        cmd.target.header.stamp = cmd.header.stamp
        cmd.target.point.x, cmd.target.point.y, cmd.target.point.z = found.point
        self._gimbal_out.publish(cmd)
        self._distance = found.distance
        if self._auto_fire:
            self._fire(now, speed)

    def _aim(self, now_ns: int) -> tuple[Target, float, AimPoint] | None:
        got, odom = self._target.get(), self._odom.get()
        if got is None or odom is None:
            reason = 'no target on /tracker/target' if got is None else 'no odometry on /odom'
        elif not got[0].tracking:
            reason = 'the tracker tracks nothing'
        elif now_ns - got[1] > self._timeout_ns:
            reason = 'the target is older than target_timeout'
        else:
            return self._solve(now_ns, got, odom[0])
        self.transition(AimState.PASSIVE, reason)
        return None

    def _solve(self, now_ns: int, got: tuple[Target, int],
               odom: Odometry) -> tuple[Target, float, AimPoint] | None:
        msg, stamp_ns = got
        try:
            target = _target_of(msg)
        except InputRejectedError as err:
            self.transition(AimState.PASSIVE, f'target refused: {err}')
            return None
        pose = odom.pose.pose.position
        origin = (pose.x, pose.y, pose.z + self._pivot_height)
        speed = self._speed()
        found = aim_point(target, (now_ns - stamp_ns) / _NS_PER_S, origin, speed,
                          self._settings)
        if found is None:
            self.transition(AimState.PASSIVE, f'out of range at {speed:.1f} m/s')
            return None
        return msg, speed, found

    def _on_shot(self, msg: RefereeShot, receive_ns: int) -> None:
        speed = float(msg.speed)
        if math.isfinite(speed) and speed > 0.0:
            self._speeds.append(speed)

    def _speed(self) -> float:
        """The muzzle speed [m/s]: measured by the referee, else the commanded one."""
        measured = list(self._speeds)
        return sum(measured) / len(measured) if measured else self._default_speed

    def _fire(self, now: Time, speed: float) -> None:
        """READY while tracking; PUSH while the barrel is on the plate."""
        firing = self._on_target() and self._wheels_ready()
        if firing and not self._firing:
            self._burst += 1  # each time the gate opens, a new (continuous) burst
        self._firing = firing
        cmd = ShootCmd(mode=ShootCmd.PUSH if firing else ShootCmd.READY,
                       speed=self._default_speed, hz=_NS_PER_S / self._fire_period_ns,
                       num=0, burst_id=self._burst)
        cmd.header.stamp = now.to_msg()
        self._shoot_out.publish(cmd)

    def _on_target(self) -> bool:
        gimbal, distance = self._gimbal.get(), self._distance
        if gimbal is None or not distance:
            return False
        state = gimbal[0]
        if state.state != GimbalCmd.TRACK:
            return False
        yaw_error = abs(wrap_to_pi(state.yaw - state.yaw_target))
        pitch_error = abs(state.pitch - state.pitch_target)
        return (yaw_error * distance < self._tolerance * self._half[0]
                and pitch_error * distance < self._tolerance * self._half[1])

    def _wheels_ready(self) -> bool:
        shooter = self._shooter.get()
        return shooter is not None and bool(shooter[0].friction_ready)


def _target_of(msg: Target) -> ArmorTarget:
    """The tracker's message as the solver's target (refused if a value is bad)."""
    return ArmorTarget(
        center=(float(msg.position.x), float(msg.position.y)), z=float(msg.position.z),
        velocity=(float(msg.velocity.x), float(msg.velocity.y), float(msg.velocity.z)),
        yaw=float(msg.yaw), v_yaw=float(msg.v_yaw), radius_1=float(msg.radius_1),
        radius_2=float(msg.radius_2), dz=float(msg.dz), armors_num=int(msg.armors_num))
