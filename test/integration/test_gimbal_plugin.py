"""rm_plugins/StandGimbal in rm_robot without a simulator: decisions and targets on topics.

The host runs the gimbal plugin alone; the test plays the bridge and the IMU by
publishing /actuator_states and /imu (and /odom) with chosen values, then reads what the
plugin decides on /gimbal_state and /actuator_cmd. The physical behaviour is tested on
the simulator in test_gimbal.py; here are the cases that need exact inputs: rejected
commands, missing data, signs of the compensation and the aiming geometry.
"""

import math
import threading

import pytest
import rclpy
from nav_msgs.msg import Odometry
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rm_base.geometry import quaternion_from_rpy, quaternion_from_yaw
from rm_base.host import RobotHost
from rm_base.plugin import ParameterError, PluginConfigError, PluginLoader
from sensor_msgs.msg import Imu
from support.ros import wait_until

from rm_msgs.msg import ActuatorCmd, ActuatorState, GimbalCmd, GimbalState

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 10.0  # longest wait for any condition [s]; normally met in well under a second

BASE = {
    'plugins': ['gimbal'],
    'gimbal.type': 'rm_plugins/StandGimbal',
    'gimbal.rate': 100.0,
    'gimbal.pitch_min': -0.4,
    'gimbal.pitch_max': 0.3,
    'gimbal.pivot_position': [0.0, 0.0, 0.3],
    'gimbal.command_timeout': 0.5,
    'gimbal.imu_timeout': 0.5,
    'gimbal.joint_timeout': 0.5,
    'gimbal.odom_timeout': 0.5,
    # Plain proportional loops, no filtering: outputs follow from the inputs directly.
    'gimbal.yaw_pid.kp': 10.0,
    'gimbal.pitch_pid.kp': 10.0,
    'gimbal.base_rate_tau': 0.0,
}


class World:
    """What the test makes the plugin see: joint states, IMU, odometry (all mutable)."""

    def __init__(self):
        self.yaw_joint = 0.0
        self.yaw_joint_velocity = 0.0
        self.pitch_joint = 0.0
        self.pitch_joint_velocity = 0.0
        self.imu_rpy = (0.0, 0.0, 0.0)
        self.imu_rate = (0.0, 0.0, 0.0)  # body frame [rad/s]
        self.imu = True
        self.odom = None  # (x, y, yaw)


class Harness:
    def __init__(self, context, **overrides):
        params = {**BASE, **overrides}
        self.host = RobotHost(
            context=context,
            parameter_overrides=[Parameter(k, value=v) for k, v in params.items()],
        )
        self.probe = rclpy.create_node('probe', context=context)
        self.executor = EventsExecutor(context=context)
        self.world = World()
        self.cmd = None
        self.states = []
        self.actuator_cmds = []
        self.probe.create_subscription(GimbalState, '/gimbal_state', self.states.append, 50)
        self.probe.create_subscription(ActuatorCmd, '/actuator_cmd', self.actuator_cmds.append, 50)
        self._pubs = {
            'cmd': self.probe.create_publisher(GimbalCmd, '/gimbal_cmd', 10),
            'joints': self.probe.create_publisher(ActuatorState, '/actuator_states', 10),
            'imu': self.probe.create_publisher(Imu, '/imu', 10),
            'odom': self.probe.create_publisher(Odometry, '/odom', 10),
        }
        self.probe.create_timer(0.01, self._publish)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)

    def start(self):
        self.executor.add_node(self.host)
        self.executor.add_node(self.probe)
        self._thread.start()
        return self

    def _publish(self):
        stamp = self.probe.get_clock().now().to_msg()
        w = self.world
        joints = ActuatorState()
        joints.header.stamp = stamp
        joints.name = ['yaw', 'pitch']
        joints.position = [w.yaw_joint, w.pitch_joint]
        joints.velocity = [w.yaw_joint_velocity, w.pitch_joint_velocity]
        joints.effort = [0.0, 0.0]
        joints.temperature = [30.0, 30.0]
        joints.online = [True, True]
        joints.error_code = [0, 0]
        self._pubs['joints'].publish(joints)
        if w.imu:
            imu = Imu()
            imu.header.stamp = stamp
            q = quaternion_from_rpy(*w.imu_rpy)
            imu.orientation.x, imu.orientation.y, imu.orientation.z, imu.orientation.w = q
            imu.angular_velocity.x, imu.angular_velocity.y, imu.angular_velocity.z = w.imu_rate
            self._pubs['imu'].publish(imu)
        if w.odom is not None:
            odom = Odometry()
            odom.header.stamp = stamp
            odom.header.frame_id = 'odom'
            x, y, yaw = w.odom
            odom.pose.pose.position.x, odom.pose.pose.position.y = x, y
            o = odom.pose.pose.orientation
            o.x, o.y, o.z, o.w = quaternion_from_yaw(yaw)
            self._pubs['odom'].publish(odom)
        if self.cmd is not None:
            cmd = self.cmd()
            cmd.header.stamp = stamp
            self._pubs['cmd'].publish(cmd)

    def command(
        self,
        mode,
        *,
        rate_yaw=0.0,
        rate_pitch=0.0,
        frame='',
        point=(0.0, 0.0, 0.0),
        bullet_speed=0.0,
    ):
        def make():
            msg = GimbalCmd()
            msg.mode = mode
            msg.rate_yaw, msg.rate_pitch = rate_yaw, rate_pitch
            msg.target.header.frame_id = frame
            msg.target.point.x, msg.target.point.y, msg.target.point.z = point
            msg.bullet_speed = bullet_speed
            return msg

        self.cmd = make

    def state(self):
        return self.states[-1] if self.states else None

    def targets(self):
        """Latest velocity targets {joint: (mode, velocity)} from the plugin."""
        if not self.actuator_cmds:
            return {}
        msg = self.actuator_cmds[-1]
        return {n: (m, v) for n, m, v in zip(msg.name, msg.mode, msg.velocity, strict=True)}

    def close(self):
        self._stop.set()
        self._thread.join()
        self.host.destroy_node()
        self.probe.destroy_node()
        self.executor.shutdown()

    def _spin(self):
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)


@pytest.fixture
def harness(ros_context):
    made = []

    def make(**overrides):
        made.append(Harness(ros_context, **overrides))
        return made[-1].start()

    yield make
    for h in made:
        h.close()


def in_state(h, mode, reason=None):
    s = h.state()
    return s is not None and s.state == mode and (reason is None or s.reason == reason)


def test_stand_gimbal_loads_by_name(harness):
    description = PluginLoader().describe('rm_plugins/StandGimbal')
    assert description.package == 'rm_plugins'
    h = harness()
    assert type(h.host.plugin('gimbal')).__module__ == 'rm_plugins.gimbal.plugin'
    assert h.host.plugin('gimbal').joints == ('yaw', 'pitch')


def test_when_the_chassis_spins_under_a_still_barrel_expect_the_joint_to_counter_rotate(harness):
    # The IMU on the barrel reads no rotation while the yaw joint turns at -3 rad/s: the
    # chassis spins at +3 rad/s (IMU rate - joint velocity). On target, the joint velocity
    # target must be -3 rad/s so the barrel stays still in the world.
    h = harness()
    h.world.yaw_joint_velocity = -3.0
    h.command(GimbalCmd.RATE)
    assert wait_until(lambda: in_state(h, GimbalCmd.RATE), WAIT)
    assert wait_until(lambda: h.targets().get('yaw', (0, 0))[1] == pytest.approx(-3.0), WAIT)
    assert h.targets()['yaw'][0] == ActuatorCmd.MODE_VELOCITY
    assert h.targets()['pitch'] == (ActuatorCmd.MODE_VELOCITY, pytest.approx(0.0))


def test_a_rate_moves_the_world_target_until_it_leads_the_barrel_by_the_maximum(harness):
    # RATE 0.5 rad/s yaw and -0.2 rad/s pitch (up). Nobody moves the barrel here, so the
    # targets run away from it: the yaw target stops at max_target_lead = 0.5 rad ahead
    # (after 1 s), where the joint velocity is kp * 0.5 + 0.5 feed-forward = 5.5 rad/s.
    # The pitch target stops at pitch_min = -0.4 rad (after 2 s), with no feed-forward
    # there: kp * -0.4 = -4 rad/s, which the limit bound limit_gain * (-0.4 - 0) allows.
    h = harness()
    h.command(GimbalCmd.RATE, rate_yaw=0.5, rate_pitch=-0.2)
    assert wait_until(lambda: in_state(h, GimbalCmd.RATE), WAIT)
    assert wait_until(lambda: h.state().yaw_target == pytest.approx(0.5), WAIT)
    assert wait_until(lambda: h.targets()['yaw'][1] == pytest.approx(5.5), WAIT)
    assert wait_until(lambda: h.state().pitch_target == pytest.approx(-0.4), WAIT)
    assert wait_until(lambda: h.targets()['pitch'][1] == pytest.approx(-4.0), WAIT)


def test_at_the_pitch_limit_expect_no_velocity_beyond_it(harness):
    # The barrel sits at pitch_max (0.3 rad down) and is told to go further down.
    h = harness()
    h.world.pitch_joint = 0.3
    h.world.imu_rpy = (0.0, 0.3, 0.0)
    h.command(GimbalCmd.RATE, rate_pitch=1.0)
    assert wait_until(lambda: in_state(h, GimbalCmd.RATE), WAIT)
    assert wait_until(lambda: 'pitch' in h.targets(), WAIT)
    for _ in range(20):  # over a few ticks: never a positive (downward) velocity
        assert h.targets()['pitch'][1] <= 1e-9
        wait_until(lambda: False, 0.01)
    assert h.state().pitch_target == pytest.approx(0.3)


def test_tracking_an_odom_point_aims_at_its_bearing(harness):
    # Chassis at (1, 0) facing +y (yaw pi/2), barrel straight ahead (joint 0, IMU yaw pi/2,
    # so the IMU's world frame is odom). Target at (1, 5, 0.3) in odom: straight ahead and
    # level with the pivot (0.3 m up): yaw target pi/2, pitch target 0 -> no motion.
    # Target at (-4, 0, 0.3): bearing pi from the pivot at (1, 0) -> the barrel must turn
    # by +-pi/2 (left, the short way: +pi/2 to pi).
    h = harness()
    h.world.odom = (1.0, 0.0, math.pi / 2)
    h.world.imu_rpy = (0.0, 0.0, math.pi / 2)
    h.command(GimbalCmd.TRACK, frame='odom', point=(1.0, 5.0, 0.3))
    assert wait_until(lambda: in_state(h, GimbalCmd.TRACK, 'tracking a point in odom'), WAIT)
    assert wait_until(lambda: h.state().yaw_target == pytest.approx(math.pi / 2, abs=1e-6), WAIT)
    assert h.state().pitch_target == pytest.approx(0.0, abs=1e-9)
    assert h.targets()['yaw'][1] == pytest.approx(0.0, abs=1e-6)
    h.command(GimbalCmd.TRACK, frame='odom', point=(-4.0, 0.0, 0.3))
    assert wait_until(lambda: abs(h.state().yaw_target) == pytest.approx(math.pi), WAIT)
    assert h.targets()['yaw'][1] > 0.0


def test_tracking_a_base_link_point_aims_relative_to_the_chassis(harness):
    # Barrel at joint 0.5 rad, IMU world yaw 1.5 rad: the chassis heads 1.0 rad in the
    # IMU's world. A point 2 m to the left of base_link and 2 m up from the pivot (z 2.3)
    # is at bearing pi/2 from the chassis (world yaw target 1.0 + pi/2) and 45 deg above
    # the pivot: pitch target -pi/4 clamped to pitch_min -0.4.
    h = harness()
    h.world.yaw_joint = 0.5
    h.world.imu_rpy = (0.0, 0.0, 1.5)
    h.command(GimbalCmd.TRACK, frame='base_link', point=(0.0, 2.0, 2.3))
    assert wait_until(lambda: in_state(h, GimbalCmd.TRACK), WAIT)
    # No odometry: GimbalState's world frame is the IMU's.
    assert wait_until(
        lambda: h.state().yaw_target == pytest.approx(1.0 + math.pi / 2, abs=1e-6), WAIT
    )
    assert h.state().pitch_target == pytest.approx(-0.4)


def test_with_a_bullet_speed_the_pitch_target_compensates_the_drop(harness):
    # No drag: the closed form. Target 8 m straight ahead, level with the pivot, 15 m/s:
    #   tan(theta) = (v^2 - sqrt(v^4 - g^2 d^2)) / (g d)
    #              = (225 - sqrt(50625 - 6154.9)) / 78.453 = 0.17996 -> theta = 0.1781 rad
    # above the line of sight: REP 103 pitch target -0.1781 (barrel up).
    h = harness(**{'gimbal.bullet_drag': 0.0, 'gimbal.barrel_length': 0.0})
    h.command(GimbalCmd.TRACK, frame='base_link', point=(8.0, 0.0, 0.3), bullet_speed=15.0)
    assert wait_until(lambda: in_state(h, GimbalCmd.TRACK, 'tracking a point in base_link'), WAIT)
    assert wait_until(lambda: h.state().pitch_target == pytest.approx(-0.1781, abs=1e-4), WAIT)
    # 5 m/s reaches at most v^2 / g = 2.55 m: out of range, aim along the line of sight.
    h.command(GimbalCmd.TRACK, frame='base_link', point=(8.0, 0.0, 0.3), bullet_speed=5.0)
    out_of_range = (
        'tracking a point in base_link: out of range at the bullet speed, '
        'aiming along the line of sight'
    )
    assert wait_until(lambda: in_state(h, GimbalCmd.TRACK, out_of_range), WAIT)
    assert wait_until(lambda: h.state().pitch_target == pytest.approx(0.0, abs=1e-9), WAIT)


def test_an_odom_target_without_odometry_holds_the_aim_and_says_why(harness):
    h = harness()
    h.command(GimbalCmd.TRACK, frame='odom', point=(3.0, 0.0, 0.3))
    assert wait_until(
        lambda: in_state(h, GimbalCmd.TRACK, 'holding the aim: no odometry on /odom'), WAIT
    )
    assert h.targets()['yaw'] == (ActuatorCmd.MODE_VELOCITY, pytest.approx(0.0))


def test_without_imu_data_expect_passive_and_joints_off(harness):
    h = harness()
    h.world.imu = False
    h.command(GimbalCmd.RATE)
    assert wait_until(lambda: in_state(h, GimbalCmd.PASSIVE, 'no IMU data on /imu'), WAIT)
    assert wait_until(lambda: h.targets().get('yaw', (None,))[0] == ActuatorCmd.MODE_OFF, WAIT)
    assert h.targets()['pitch'][0] == ActuatorCmd.MODE_OFF
    assert math.isnan(h.state().yaw) and math.isnan(h.state().yaw_target)


@pytest.mark.parametrize(
    ('command', 'reason'),
    [
        ({'mode': 7}, 'rejected /gimbal_cmd: unknown mode 7 (known: 0=PASSIVE, 1=RATE, 2=TRACK)'),
        (
            {'mode': GimbalCmd.RATE, 'rate_yaw': math.nan},
            'rejected /gimbal_cmd: rate_yaw and rate_pitch must be finite, got (nan, 0.0)',
        ),
        (
            {'mode': GimbalCmd.TRACK, 'frame': 'odom', 'point': (math.inf, 0.0, 0.0)},
            'rejected /gimbal_cmd: target (inf, 0.0, 0.0) and bullet_speed 0.0 must be finite',
        ),
        (
            {'mode': GimbalCmd.TRACK, 'frame': 'map', 'point': (1.0, 0.0, 0.0)},
            "rejected command: unknown target frame 'map' (known: odom, world, base_link, muzzle, "
            'pitch_link, yaw_link)',
        ),
    ],
    ids=['unknown-mode', 'nan-rate', 'inf-target', 'unknown-frame'],
)
def test_a_bad_command_is_rejected_with_the_reason_and_never_reaches_a_motor(
    harness, command, reason
):
    h = harness()
    mode = command.pop('mode')
    h.command(mode, **command)
    assert wait_until(lambda: in_state(h, GimbalCmd.PASSIVE, reason), WAIT)
    assert wait_until(lambda: h.targets().get('yaw', (None,))[0] == ActuatorCmd.MODE_OFF, WAIT)
    sent = {m for msg in h.actuator_cmds for m in msg.mode}
    assert sent == {ActuatorCmd.MODE_OFF}


@pytest.mark.parametrize(
    ('overrides', 'error', 'message'),
    [
        (
            {'gimbal.pitch_min': 0.3, 'gimbal.pitch_max': -0.3},
            PluginConfigError,
            r'pitch_min \(0.3 rad\) must be below pitch_max',
        ),
        (
            {'gimbal.pitch_min': None},
            ParameterError,
            r"parameter 'gimbal.pitch_min' is required but not set",
        ),
        (
            {'gimbal.pitch_joint': 'yaw'},
            PluginConfigError,
            "yaw_joint and pitch_joint are both 'yaw'",
        ),
        (
            {'gimbal.base_frames': ['odom']},
            PluginConfigError,
            'frame.s. odom in both world_frames and base_frames',
        ),
        (
            {'gimbal.frames.mounts': ['camera'], 'gimbal.frames.camera.parent': 'turret'},
            PluginConfigError,
            "frames.camera.parent is 'turret', not one of base_link, yaw_link, pitch_link",
        ),
        (
            {'gimbal.frames.mounts': ['camera']},
            ParameterError,
            r"parameter 'gimbal.frames.camera.parent' is required but not set",
        ),
        (
            {'gimbal.frames.mounts': ['yaw_link'], 'gimbal.frames.yaw_link.parent': 'base_link'},
            PluginConfigError,
            'gimbal frames must have distinct names',
        ),
    ],
    ids=[
        'limits-order', 'limit-missing', 'same-joint', 'frame-twice', 'mount-parent',
        'mount-parent-missing', 'mount-twice',
    ],
)
def test_a_bad_config_is_one_clear_error(ros_context, overrides, error, message):
    params = {**BASE, **overrides}
    params = {k: v for k, v in params.items() if v is not None}
    with pytest.raises(error, match=message):
        RobotHost(
            context=ros_context,
            parameter_overrides=[Parameter(k, value=v) for k, v in params.items()],
        )
