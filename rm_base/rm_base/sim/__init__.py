"""Simulated CAN interface ``rm_sim`` and motor/robot physics (no rclpy).

``can.Bus(interface='rm_sim', channel='can0', motors=[...])`` opens a :class:`SimBus`;
:class:`SimWorld` holds the channels, motors, robot body and IMUs that share one clock.
"""

from rm_base.sim.body import Mount, RobotBody
from rm_base.sim.body_config import body_from_config
from rm_base.sim.bus import DEFAULT_RX_QUEUE_SIZE, SimBus
from rm_base.sim.channel import ChannelStats, SimChannel, channel_names, find_channel
from rm_base.sim.device_config import check_channel, device_from_config
from rm_base.sim.image_link import SimImageLink
from rm_base.sim.imu import SimImu, imu_from_config
from rm_base.sim.joint import Joint
from rm_base.sim.launcher import Launcher, Shot
from rm_base.sim.pty_port import PtyPort, expand_path
from rm_base.sim.referee import SimReferee
from rm_base.sim.remote import SimRemote
from rm_base.sim.world import SimWorld, Timing, load_config
from rm_base.sim_devices.device import DeviceStats, SimDevice
from rm_base.sim_devices.errors import SimConfigError, SimError, SimLookupError, SimStateError
from rm_base.sim_devices.faults import Fault, FaultKind
from rm_base.sim_devices.mit_device import MitDevice
from rm_base.sim_devices.motor import DJI_ENCODER_COUNTS, DriveMode, MotorModel
from rm_base.sim_devices.motor_params import MOTOR_DEFAULTS, MotorParams, MotorType, motor_params

__all__ = [
    'DEFAULT_RX_QUEUE_SIZE',
    'DJI_ENCODER_COUNTS',
    'MOTOR_DEFAULTS',
    'ChannelStats',
    'DeviceStats',
    'DriveMode',
    'Fault',
    'FaultKind',
    'Joint',
    'Launcher',
    'MitDevice',
    'MotorModel',
    'MotorParams',
    'MotorType',
    'Mount',
    'PtyPort',
    'RobotBody',
    'Shot',
    'SimBus',
    'SimChannel',
    'SimConfigError',
    'SimDevice',
    'SimError',
    'SimImageLink',
    'SimImu',
    'SimLookupError',
    'SimReferee',
    'SimRemote',
    'SimStateError',
    'SimWorld',
    'Timing',
    'body_from_config',
    'channel_names',
    'check_channel',
    'device_from_config',
    'expand_path',
    'find_channel',
    'imu_from_config',
    'load_config',
    'motor_params',
]
