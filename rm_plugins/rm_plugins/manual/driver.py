"""The operator's input -> the four commands, by the mapping. Pure: no rclpy.

The DR16 frame gives the switches, the sticks and (through the remote's PC port) the
keyboard and mouse; the image link's keyboard/mouse (0x0304 or the ``A9 53`` remote frame)
adds to them: keys are or-ed, mouse speeds summed. The right switch says who drives
(:class:`~rm_plugins.manual.mapping.Drive`); the keyboard's mode keys and friction key
toggle on each press, so :class:`ManualDriver` remembers the keys held at the last input.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Twist
from rm_base.hardware.protocols.dbus import CHANNEL_RANGE, DbusFrame, Key, Switch

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd
from rm_plugins.manual.mapping import Drive, ManualMapping, Stick

_POSITION = {Switch.UP: 'up', Switch.MID: 'mid', Switch.DOWN: 'down'}


@dataclass(frozen=True)
class Keyboard:
    """A keyboard and mouse (the image link's): speeds as sent, buttons and keys held."""

    mouse_x: int = 0
    mouse_y: int = 0
    left: bool = False
    right: bool = False
    keys: int = 0


@dataclass(frozen=True)
class OperatorInput:
    """What the operator does at one instant.

    Attributes:
        sticks: channels 0..3 of the DR16, -1..1 (full stick).
        right, left: switch positions, 'up' | 'mid' | 'down'.
        mouse_x, mouse_y: mouse speeds as sent (x > 0 right, y > 0 down).
        mouse_left, mouse_right: buttons held.
        keys: keyboard bitmap (rm_base.hardware.protocols.dbus.Key).
    """

    sticks: tuple[float, float, float, float]
    right: str
    left: str
    mouse_x: int = 0
    mouse_y: int = 0
    mouse_left: bool = False
    mouse_right: bool = False
    keys: int = 0

    @classmethod
    def from_dbus(cls, frame: DbusFrame, mapping: ManualMapping) -> OperatorInput:
        """The input a DR16 frame carries."""
        c0, c1, c2, c3 = (c / CHANNEL_RANGE for c in frame.channels)
        return cls(
            (c0, c1, c2, c3),
            _POSITION[getattr(frame, mapping.right_switch)],
            _POSITION[getattr(frame, mapping.left_switch)],
            frame.mouse[0], frame.mouse[1], frame.mouse_left, frame.mouse_right, frame.keys,
        )

    def plus_keyboard(self, k: Keyboard) -> OperatorInput:
        """This input with another keyboard and mouse (the image link's) added."""
        return OperatorInput(
            self.sticks, self.right, self.left, self.mouse_x + k.mouse_x,
            self.mouse_y + k.mouse_y, self.mouse_left or k.left, self.mouse_right or k.right,
            self.keys | k.keys,
        )


@dataclass(frozen=True)
class Commands:
    """One set of commands (the fields of ChassisCmd, Twist, GimbalCmd and ShootCmd used)."""

    chassis_mode: int
    vx: float
    vy: float
    gimbal_mode: int
    yaw_rate: float
    pitch_rate: float
    shoot_mode: int
    bullet_speed: float = 0.0
    hz: float = 0.0
    burst_id: int = 0
    speed_gear: int = ChassisCmd.GEAR_NORMAL


def command_messages(c: Commands, stamp: Time) -> dict[str, Any]:
    """The messages of c, stamped, by topic name (``chassis_cmd``, ``vel_cmd``, ...)."""
    chassis = ChassisCmd(mode=c.chassis_mode, speed_gear=c.speed_gear)
    chassis.header.stamp = stamp
    vel = Twist()
    vel.linear.x, vel.linear.y = c.vx, c.vy
    gimbal = GimbalCmd(mode=c.gimbal_mode, rate_yaw=c.yaw_rate, rate_pitch=c.pitch_rate)
    gimbal.header.stamp = stamp
    shoot = ShootCmd(mode=c.shoot_mode, speed=c.bullet_speed, hz=c.hz, num=0,
                     burst_id=c.burst_id)
    shoot.header.stamp = stamp
    return {'chassis_cmd': chassis, 'vel_cmd': vel, 'gimbal_cmd': gimbal, 'shoot_cmd': shoot}


def passive(burst_id: int = 0) -> Commands:
    """Every mechanism PASSIVE."""
    return Commands(
        ChassisCmd.PASSIVE, 0.0, 0.0, GimbalCmd.PASSIVE, 0.0, 0.0, ShootCmd.PASSIVE,
        burst_id=burst_id,
    )


class ManualDriver:
    """Commands from operator input (see the module docstring).

    Attributes:
        mapping: the mapping in use.
    """

    def __init__(self, mapping: ManualMapping) -> None:
        self.mapping = mapping
        self._keys = 0
        self._chassis_key: int | None = None  # the mode key toggled on, if any
        self._friction = False
        self._firing = False
        self._burst_id = 0

    def lost(self) -> Commands:
        """The remote is silent: everything PASSIVE, the toggles off."""
        self._keys = 0
        self._chassis_key = None
        self._friction = self._firing = False
        return passive(self._burst_id)

    def commands(self, operator: OperatorInput) -> Commands:
        """The commands for this input."""
        drive = self.mapping.modes[operator.right]
        pressed = operator.keys & ~self._keys
        self._keys = operator.keys
        if drive is Drive.PASSIVE:
            self._chassis_key, self._friction, self._firing = None, False, False
            return passive(self._burst_id)
        if drive is Drive.REMOTE:
            return self._remote(operator)
        return self._keyboard(operator, pressed)

    def _remote(self, operator: OperatorInput) -> Commands:
        m, s = self.mapping.remote, self.mapping
        shoot = m.shooter[operator.left]
        self._new_burst_on(shoot == ShootCmd.PUSH)
        return Commands(
            m.chassis_mode, _stick(operator, m.vx), _stick(operator, m.vy), GimbalCmd.RATE,
            _stick(operator, m.yaw_rate), _stick(operator, m.pitch_rate), shoot,
            s.shot_speed, s.shot_hz, self._burst_id,
        )

    def _keyboard(self, operator: OperatorInput, pressed: int) -> Commands:
        m, s = self.mapping.keyboard, self.mapping
        for key in m.chassis_keys:
            if pressed & key:
                self._chassis_key = None if self._chassis_key == key else key
        if pressed & m.friction_key:
            self._friction = not self._friction
        keys = operator.keys
        speed = m.speed
        # the chassis scales by its own gears.<gear> factors (one place for them)
        gear = next((g for key, g in m.gears.items() if keys & key), ChassisCmd.GEAR_NORMAL)
        vx = speed * (bool(keys & Key.W) - bool(keys & Key.S))
        vy = speed * (bool(keys & Key.A) - bool(keys & Key.D))
        held = operator.mouse_left if m.fire == 'left' else operator.mouse_right
        firing = self._friction and held
        self._new_burst_on(firing)
        shoot = ShootCmd.PUSH if firing else ShootCmd.READY if self._friction else ShootCmd.PASSIVE
        chassis = m.chassis_mode if self._chassis_key is None else m.chassis_keys[self._chassis_key]
        return Commands(
            chassis, vx, vy, GimbalCmd.RATE, operator.mouse_x * m.mouse_yaw,
            operator.mouse_y * m.mouse_pitch, shoot, s.shot_speed, s.shot_hz, self._burst_id,
            speed_gear=gear,
        )

    def _new_burst_on(self, firing: bool) -> None:
        """A new burst id each time firing starts (the shooter fires on a new id)."""
        if firing and not self._firing:
            self._burst_id = (self._burst_id + 1) & 0xFFFFFFFF
        self._firing = firing


def _stick(operator: OperatorInput, stick: Stick) -> float:
    return operator.sticks[stick.channel] * stick.scale
