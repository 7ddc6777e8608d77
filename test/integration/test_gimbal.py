"""rm_plugins/StandGimbal end to end on the simulator: commands in, physical outcome out.

Each test runs the simulated standard robot in lockstep (``support.lockstep``: the loop,
the gimbal plugin and rm_sim stepped together on a simulated clock, the simulated Hi220's
frames decoded as the Hi220 plugin does), streams /gimbal_cmd like an operator and checks
the sim's ground truth: the barrel's world yaw = chassis yaw + yaw joint angle, its pitch
= the pitch joint angle (the sim chassis stays level).

Disturbances: the chassis is spun and driven by commanding its wheel joints directly
(velocity targets from the mecanum inverse kinematics), so no chassis plugin is involved:
the gimbal is tested on a chassis that moves exactly as told. TRACK gets its odometry from
the sim's ground truth (a perfect odometry).

Errors are judged on the 90th percentile of samples taken every 20 ms over 2 s, plus a
bound on the worst sample that a lost aim (an error growing without bound) would break;
the same numbers come out on every run.
"""

from __future__ import annotations

import itertools
import math

import pytest
from nav_msgs.msg import Odometry
from rm_base.geometry import WheelKinematics, mecanum_wheels, quaternion_from_yaw
from support.lockstep import LockstepRobot

from rm_msgs.msg import ActuatorCmd, GimbalCmd

pytestmark = [pytest.mark.ros, pytest.mark.slow]

WAIT = 10.0  # longest wait for a condition [s]
SAMPLE_PERIOD = 0.02  # [s] between ground-truth samples
WINDOW = 2.0  # [s] of samples per check


class GimbalSim:
    """A LockstepRobot with the gimbal's view of it: ground truth, wheel drive, odometry."""

    def __init__(self, plugins=('imu', 'gimbal'), gimbal=None, bridge=None):
        overrides = {'rm_robot': {f'gimbal.{k}': v for k, v in (gimbal or {}).items()}}
        overrides['can_bridge'] = dict(bridge or {})
        self.robot = LockstepRobot(plugins=tuple(plugins), overrides=overrides)
        self.robot.watch('/gimbal_state', keep_history=True)
        self.gimbal = self.robot.plugin('gimbal')
        p = self.robot.host_parameters
        self.wheels = list(p['chassis.wheel_joints'])
        self.kinematics = WheelKinematics(
            mecanum_wheels(
                p['chassis.wheelbase'],
                p['chassis.track'],
                p['chassis.wheel_radius'],
                roller_signs=p['chassis.roller_signs'],
            )
        )

    def close(self):
        self.robot.close()

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
        """Keep publishing a GimbalCmd at 50 Hz (replacing the previous one)."""
        msg = GimbalCmd(
            mode=mode, rate_yaw=rate_yaw, rate_pitch=rate_pitch, bullet_speed=bullet_speed
        )
        msg.target.header.frame_id = frame
        msg.target.point.x, msg.target.point.y, msg.target.point.z = point
        self.robot.publish('/gimbal_cmd', msg, rate_hz=50.0)

    def drive_wheels(self, vx=0.0, vy=0.0, wz=0.0):
        """Drive the wheel joints (velocity targets) for a body twist, as /actuator_cmd would."""
        speeds = [float(s) for s in self.kinematics.inverse((vx, vy, wz))]
        self.robot.drive_joints(
            {w: {'mode': ActuatorCmd.MODE_VELOCITY, 'velocity': v}
             for w, v in zip(self.wheels, speeds, strict=True)}
        )

    def publish_ground_truth_odom(self, topic='/odom', rate_hz=100.0):
        """Hand odometry from the sim's body to the gimbal: a perfect odometry."""

        def make():
            x, y, yaw, _, _ = self.body()
            vx, vy, wz = self.twist()
            msg = Odometry()  # stamped on the sim clock when handed over
            msg.header.frame_id, msg.child_frame_id = 'odom', 'base_link'
            msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
            o = msg.pose.pose.orientation
            o.x, o.y, o.z, o.w = quaternion_from_yaw(yaw)
            msg.twist.twist.linear.x, msg.twist.twist.linear.y = vx, vy
            msg.twist.twist.angular.z = wz
            return msg

        self.robot.publish(topic, make, rate_hz=rate_hz)

    # -- ground truth -------------------------------------------------------------------
    def body(self):
        """Chassis x, y [m], yaw [rad] (unwrapped), yaw and pitch joint angles [rad]."""
        world = self.robot.world
        with world.lock:
            b = world.body
            return b.x, b.y, b.yaw, b.gimbal_yaw, b.gimbal_pitch

    def twist(self):
        world = self.robot.world
        with world.lock:
            return tuple(world.body.twist)

    def barrel(self):
        """Barrel world yaw (unwrapped) and pitch [rad]."""
        _, _, yaw, yaw_joint, pitch = self.body()
        return yaw + yaw_joint, pitch

    def sim_time(self):
        return self.robot.t

    def state(self):
        return self.robot.latest('/gimbal_state')

    def in_state(self, mode):
        state = self.state()
        return state is not None and state.state == mode

    def settle(self, seconds):
        """Let seconds of simulated time pass."""
        self.robot.run(seconds)

    def sample(self, measure, mode, duration=WINDOW):
        """measure() every SAMPLE_PERIOD over duration [s] of simulated time.

        Returns:
            The values, and '' or, if the gimbal left its mode meanwhile, the states it
            was in (for the assertion message).
        """
        values, left = [], set()
        for _ in range(round(duration / SAMPLE_PERIOD)):
            values.append(measure())
            if self.gimbal.state.value != mode:
                left.add((self.gimbal.state.name, self.gimbal.reason))
            self.robot.run(SAMPLE_PERIOD)
        return values, (f'the gimbal left its mode: {sorted(left)}' if left else '')


@pytest.fixture
def sim():
    made = []

    def make(**kwargs):
        made.append(GimbalSim(**kwargs))
        return made[-1]

    yield make
    for s in made:
        s.close()


def wrap(angle):
    return math.remainder(angle, 2 * math.pi)


def p90(values):
    ordered = sorted(abs(v) for v in values)
    return ordered[int(0.9 * (len(ordered) - 1))]


# The yaw loop in the incremental form (RoboMaster firmware's) with a tracking
# differentiator on its target: the same gains, the same outcome. Over the 4 s the world
# yaw passes +-pi, where an unwrapped angle error would saturate the loop.
INCREMENTAL_YAW = {'yaw_pid.form': 'incremental', 'yaw_pid.td_acceleration_limit': 200.0}


@pytest.mark.parametrize('gimbal', [{}, INCREMENTAL_YAW], ids=['positional', 'incremental'])
def test_when_rate_yaw_is_commanded_expect_the_barrel_to_turn_at_that_rate_in_the_world(
    sim, gimbal
):
    s = sim(gimbal=gimbal)
    s.command(GimbalCmd.RATE, rate_yaw=1.0)
    assert s.robot.wait_until(lambda: s.in_state(GimbalCmd.RATE), WAIT)
    s.settle(1.0)  # past the start-up transient (loop time constant 1 / kp = 0.05 s)
    samples, why = s.sample(lambda: (s.sim_time(), s.barrel()[0]), GimbalCmd.RATE, 3.0)
    (t0, yaw0), (t1, yaw1) = samples[0], samples[-1]
    rate = (yaw1 - yaw0) / (t1 - t0)
    # 1 rad/s commanded; the barrel follows the integrated target with a lag of about
    # rate / kp = 0.05 rad that varies by a few hundredths, so over 3 s the mean rate is
    # 1 rad/s within +-5 %.
    assert rate == pytest.approx(1.0, rel=0.05), why
    steps = [b - a for (_, a), (_, b) in itertools.pairwise(samples)]
    assert max(steps) < 0.03 and min(steps) > 0.01, why  # 0.02 rad per sample, no jump
    assert s.state().reason == 'rates held in the world frame'


# A turret with mass: 0.05 kg*m^2 about the yaw axis, a 0.01 kg*m^2 barrel whose weight
# pulls it down with 0.2 N*m, and the bridge's velocity loops sized for them: kp / J = 30
# rad/s for the yaw, 50 rad/s for the pitch. (standard.yaml's yaw kp of 0.12 N*m/(rad/s)
# would give this turret a 2.4 rad/s velocity loop, far too slow for a spinning chassis.)
HEAVY_TURRET = {
    'joints.yaw.sim.load_inertia': 0.05,
    'joints.pitch.sim.load_inertia': 0.01,
    'sim.body.gimbal.pitch.gravity_torque': 0.2,
    'joints.yaw.velocity_pid.kp': 1.5,
    'joints.yaw.velocity_pid.ki': 10.0,
    'joints.pitch.velocity_pid.kp': 0.5,
    'joints.pitch.velocity_pid.ki': 5.0,
}


@pytest.mark.parametrize('bridge', [{}, HEAVY_TURRET], ids=['standard-sim', 'heavy-turret'])
def test_when_rate_is_zero_and_the_chassis_spins_expect_the_world_yaw_held(sim, bridge):
    s = sim(bridge=bridge)
    s.command(GimbalCmd.RATE)
    assert s.robot.wait_until(lambda: s.in_state(GimbalCmd.RATE), WAIT)
    chassis0 = s.body()[2]
    s.drive_wheels(wz=6.0)  # a GYRO-like spin, 6 rad/s (~1 turn/s)
    s.settle(1.0)  # the wheels spin up in ~0.5 s; the chassis accelerates meanwhile
    headings, why = s.sample(lambda: s.barrel()[0], GimbalCmd.RATE)
    assert s.body()[2] - chassis0 > 2 * 2 * math.pi  # two turns under the gimbal at least
    held = sorted(headings)[len(headings) // 2]
    errors = [wrap(h - held) for h in headings]
    # The barrel's world heading over the window, about its median (an uncompensated
    # gimbal would turn 12 rad with the chassis in 2 s). Bounds: 0.03 rad (1.7 deg) for
    # 90 % of the samples, 0.15 rad for the worst (a compensation that lags by a plugin
    # period or two is far inside it; a lost one grows past it in 25 ms).
    assert p90(errors) < 0.03, (why, errors)
    assert max(abs(e) for e in errors) < 0.15, (why, errors)


def test_when_tracking_a_world_point_while_the_chassis_drives_and_spins_expect_the_aim_kept(
    sim,
):
    s = sim()
    s.publish_ground_truth_odom()
    pivot_z = s.gimbal.config.pivot[2]
    target = (3.0, 2.0, pivot_z)  # [m] in odom, level with the pivot
    s.command(GimbalCmd.TRACK, frame='odom', point=target)
    assert s.robot.wait_until(lambda: s.in_state(GimbalCmd.TRACK), WAIT)
    # 1 m/s forward while spinning at 4 rad/s: the chassis runs round a 0.25 m circle, so
    # the bearing of the target swings while the chassis turns under the gimbal.
    s.drive_wheels(vx=1.0, wz=4.0)
    s.settle(1.5)

    def aim_error():
        x, y, _, _, _ = s.body()
        return wrap(s.barrel()[0] - math.atan2(target[1] - y, target[0] - x))

    errors, why = s.sample(aim_error, GimbalCmd.TRACK)
    # Bounds: 0.04 rad (0.14 m at the 3.6 m range) for 90 % of the samples, 0.2 rad for
    # the worst one.
    assert p90(errors) < 0.04, (why, errors)
    assert max(abs(e) for e in errors) < 0.2, (why, errors)
    # Level target: level barrel.
    assert abs(s.barrel()[1]) < 0.02
    assert s.state().reason == 'tracking a point in odom'


def test_pitch_never_drives_past_its_limits(sim):
    s = sim()
    cfg = s.gimbal.config
    s.command(GimbalCmd.RATE, rate_pitch=2.0)  # down at 2 rad/s
    # Near a limit the joint slows down to limit_gain * (distance to the limit), 10 1/s:
    # the last 0.02 rad take about 0.3 s, hence the half second of settling.
    assert s.robot.wait_until(lambda: abs(s.barrel()[1] - cfg.pitch_max) < 0.02, WAIT)
    s.settle(0.5)
    lows, why_low = s.sample(lambda: s.barrel()[1], GimbalCmd.RATE, 1.0)
    s.command(GimbalCmd.RATE, rate_pitch=-2.0)  # up
    assert s.robot.wait_until(lambda: abs(s.barrel()[1] - cfg.pitch_min) < 0.02, WAIT)
    s.settle(0.5)
    highs, why_high = s.sample(lambda: s.barrel()[1], GimbalCmd.RATE, 1.0)
    # The target is clamped to the limits and the joint velocity is bounded near them, so
    # the barrel rests at the limit: within 0.02 rad of it, never more than that beyond.
    assert cfg.pitch_max - 0.02 <= min(lows), why_low
    assert max(lows) <= cfg.pitch_max + 0.02, why_low
    assert cfg.pitch_min - 0.02 <= min(highs), why_high
    assert max(highs) <= cfg.pitch_min + 0.02, why_high


def test_bullet_drop_compensation_raises_the_barrel_by_the_expected_angle(sim):
    # No drag, so the expected angle has a closed form. Target 8 m straight ahead of the
    # pivot and level with it, muzzle speed 15 m/s, g = 9.80665 m/s^2:
    #   tan(theta) = (v^2 - sqrt(v^4 - g^2 d^2)) / (g d)
    #              = (225 - sqrt(50625 - 6154.9)) / 78.453 = 14.118 / 78.453 = 0.17996
    #   theta = 0.1781 rad (10.2 deg) above the line of sight: REP 103 pitch -0.1781.
    s = sim(gimbal={'bullet_drag': 0.0, 'barrel_length': 0.0})
    point = (8.0, 0.0, s.gimbal.config.pivot[2])  # base_link: 8 m ahead, at pivot height
    s.command(GimbalCmd.TRACK, frame='base_link', point=point)
    assert s.robot.wait_until(lambda: abs(s.barrel()[1]) < 0.01, WAIT)
    line_of_sight, why = s.sample(lambda: s.barrel()[1], GimbalCmd.TRACK, 0.5)
    level = sum(line_of_sight) / len(line_of_sight)
    assert level == pytest.approx(0.0, abs=0.01), why
    s.command(GimbalCmd.TRACK, frame='base_link', point=point, bullet_speed=15.0)
    assert s.robot.wait_until(lambda: abs(s.barrel()[1] + 0.1781) < 0.01, WAIT)
    # reaching it is not settling there: the pitch loop rings after its first pass, so
    # let it settle first
    s.settle(0.5)
    compensated, why = s.sample(lambda: s.barrel()[1], GimbalCmd.TRACK, 0.5)
    raised = sum(compensated) / len(compensated)
    assert raised - level == pytest.approx(-0.1781, abs=0.01), why
    assert s.state().pitch_target == pytest.approx(-0.1781, abs=1e-3)


def test_when_commands_stop_expect_passive_and_the_joints_limp(sim):
    s = sim()
    s.command(GimbalCmd.RATE)
    assert s.robot.wait_until(lambda: s.in_state(GimbalCmd.RATE), WAIT)
    joint = s.robot.joint
    assert s.robot.wait_until(
        lambda: joint('yaw')['mode'] == joint('pitch')['mode'] == ActuatorCmd.MODE_VELOCITY,
        WAIT,
    )
    s.robot.stop_publishing('/gimbal_cmd')
    assert s.robot.wait_until(lambda: s.in_state(GimbalCmd.PASSIVE), WAIT)
    reason = s.state().reason
    assert reason.startswith('no command on /gimbal_cmd for '), reason
    assert reason.endswith('(timeout 0.250 s)'), reason
    # The bridge applies MODE_OFF: zero current, the barrel is free.
    assert s.robot.wait_until(
        lambda: joint('yaw')['mode'] == joint('pitch')['mode'] == ActuatorCmd.MODE_OFF, WAIT
    )
