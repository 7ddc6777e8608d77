"""A small plugin for PluginBase's tests: drives 'wheel' at the commanded speed.

With the clock helpers the tests use: ``at(ns)``, ``MS``, ``T0``; ``command`` hands the
plugin a command as its subscription would, ``modes`` reads a sent ActuatorCmd.
"""

import enum

from geometry_msgs.msg import TwistStamped
from rclpy.time import Time
from rm_base.plugin import JointTarget, PluginBase

MS = 1_000_000  # [ns]
T0 = 1_000_000 * MS  # [ns]


def at(ns):
    return Time(nanoseconds=ns)


class Wheel(enum.IntEnum):
    PASSIVE = 0
    DRIVE = 1


class WheelPlugin(PluginBase):
    """Drives 'wheel' at the commanded linear.x [rad/s]; remembers what happened."""

    State = Wheel

    def on_init(self):
        self.gain = self.params.double('gain', 1.0, description='gain', unit='1')
        self.claim_joints(['wheel'])
        self.cmd = self.subscribe_command('wheel_cmd', TwistStamped)
        self.events = []
        self.integral = 0.0

    def update(self, now, dt):
        self.events.append(('update', round(dt, 6)))
        cmd = self.cmd.latest(now.nanoseconds)
        self.integral += dt
        self.transition(Wheel.DRIVE, 'commanded')
        velocity = self.gain * cmd.twist.linear.x
        self.send_joint_targets({'wheel': JointTarget.with_velocity(velocity)})

    def on_reset(self):
        self.events.append('reset')
        self.integral = 0.0

    def on_disable(self):
        self.events.append('on_disable')


def command(plugin, velocity, receive_ns):
    msg = TwistStamped()
    msg.twist.linear.x = velocity
    plugin.cmd.handle(msg, receive_ns)


def modes(msg):
    return dict(zip(msg.name, msg.mode, strict=True))
