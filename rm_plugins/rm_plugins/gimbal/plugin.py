"""StandGimbal: a yaw/pitch gimbal stabilised in the world by its IMU.

Why one module: the mode decision (RATE, TRACK in any frame) and the control tick; config,
aim and loops are modules of their own.

Inputs:
    /gimbal_cmd (rm_msgs/GimbalCmd, watched): the mode, rates or target point.
    /imu (sensor_msgs/Imu): orientation and rates of the gimbal (the IMU is on it).
    /odom (nav_msgs/Odometry): the chassis pose, for targets given in the odom frame.
    the yaw and pitch joints' states (through the framework).
Outputs:
    velocity targets of the yaw and pitch joints, every run (the actuators directly in
    the one-process robot, /actuator_cmd otherwise).
    /gimbal_state (rm_msgs/GimbalState): state, reason, world angles, targets, joints.
    /tf: base_link -> yaw_link -> pitch_link from the joints, every ``frames.rate``;
    /tf_static: the muzzle (``barrel_length`` along the barrel) and ``frames.mounts``.

States (``GimbalMode``, numbered as ``GimbalCmd``), all chosen in ``_decide``:

- PASSIVE: joints off (limp). Commanded, or no command within ``command_timeout`` (the
  watchdog; limp is every mechanism's safe state: a gimbal that lost its operator must
  not keep driving), or a command rejected as invalid (NaN, unknown mode or frame), or the
  IMU or a joint has no fresh data (no stabilisation is possible without them).
- RATE: ``rate_yaw``/``rate_pitch`` (clamped to the axis' max_rate) are integrated into
  a target held in the *world* frame, so the aim stays put while the chassis turns or
  spins; the target never leads the barrel by more than ``max_target_lead``.
- TRACK: aim at ``target`` (a point in an odom/world frame, in base_link, or in any frame
  of the robot's TF tree, e.g. a camera's: put in odom once per command) and keep aiming
  as the chassis moves; with ``bullet_speed > 0`` the pitch compensates the drop
  (``rm_base.geometry.aim``, from the muzzle ``barrel_length`` along the barrel). Without
  fresh odometry an odom target holds the aim. The IMU's world frame is tied to odom by
  a slowly filtered yaw offset (chassis heading by IMU minus yaw joint, against the odom
  heading), so the loops run on the IMU while targets come in odom.

Control (see ``rm_plugins.gimbal.control``): an angle PID per axis on the IMU's world
angle gives a world rate; the joint velocity target is that rate minus the rate of the
joint's base (IMU rate minus joint velocity: the chassis spin for yaw), and the joint's
own 1 kHz velocity loop in the control loop closes it on the motor encoder. The IMU gyro
enters every run as that base-rate feed-forward; in TRACK the line of sight's own rate
(from the odometry twist) is fed forward too.

Pitch is clamped to ``[pitch_min, pitch_max]`` twice: the world target is clamped to what
those joint limits allow, and the joint velocity is bounded near a limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from nav_msgs.msg import Odometry
from rclpy.qos import qos_profile_sensor_data
from rclpy.time import Time
from rm_base.errors import InputRejectedError
from rm_base.geometry import rpy_from_quaternion, wrap_to_pi, yaw_from_quaternion
from rm_base.geometry.aim import AimSolution, aim_from_point
from rm_base.geometry.frame_tree import FrameLookupError
from rm_base.plugin import JointTarget, LatestMessage, PluginBase
from sensor_msgs.msg import Imu

from rm_msgs.msg import GimbalCmd, GimbalState
from rm_plugins.gimbal.commands import GimbalMode, GimbalRequest, parse_gimbal_cmd
from rm_plugins.gimbal.config import GimbalConfig, GimbalTuning, read_config, with_tuning
from rm_plugins.gimbal.control import AxisLoop, PlanarPose, Smoother, clamp, sight_rates
from rm_plugins.gimbal.frames import joint_links, mount_links

_NS_PER_S = 1_000_000_000
@dataclass(frozen=True)
class Measurement:
    """The gimbal now: IMU values brought forward to this tick with their rates.

    Attributes:
        yaw: barrel heading in the IMU's world frame [rad].
        pitch: barrel pitch, positive down [rad].
        yaw_rate: world yaw rate [rad/s].
        pitch_rate: pitch rate about the barrel's y axis [rad/s].
        yaw_joint, pitch_joint: joint angles [rad].
        yaw_joint_velocity, pitch_joint_velocity: [rad/s].
    """

    yaw: float
    pitch: float
    yaw_rate: float
    pitch_rate: float
    yaw_joint: float
    pitch_joint: float
    yaw_joint_velocity: float
    pitch_joint_velocity: float

    @property
    def base_yaw(self) -> float:
        """Heading of the chassis (the yaw joint's base) in the IMU's world frame [rad]."""
        return self.yaw - self.yaw_joint


@dataclass(frozen=True)
class _Odom:
    """The chassis in the odom frame, brought forward to this tick.

    Attributes:
        pose: planar pose (x, y [m], yaw [rad]).
        z: height of base_link [m].
        vx, vy, wz: body twist [m/s, m/s, rad/s].
    """

    pose: PlanarPose
    z: float
    vx: float
    vy: float
    wz: float


@dataclass(frozen=True)
class _Aim:
    """A TRACK decision: world targets (IMU world frame) and their rates.

    Attributes:
        yaw, pitch: targets [rad].
        yaw_rate, pitch_rate: feed-forward [rad/s] from the chassis' own motion.
        follows_base: the target is fixed to the chassis; its yaw turns with it, so the
            chassis' yaw rate is added to yaw_rate.
    """

    yaw: float
    pitch: float
    yaw_rate: float = 0.0
    pitch_rate: float = 0.0
    follows_base: bool = False


class StandGimbal(PluginBase):
    """Yaw/pitch gimbal: PASSIVE, RATE (IMU-stabilised), TRACK (aim at a point).

    Parameters: see ``rm_plugins.gimbal.config.read_config`` and the ``gimbal:`` section of
    rm_bringup/config/standard.yaml.
    """

    State = GimbalMode

    def on_init(self) -> None:
        """Read the config, claim the joints, subscribe and create the state publisher."""
        self.config: GimbalConfig = read_config(self.params, self.read_config(GimbalTuning))
        cfg = self.config
        self.claim_joints([cfg.yaw.joint, cfg.pitch.joint],
                          limits={cfg.pitch.joint: (cfg.pitch_min, cfg.pitch_max)})
        self.command = self.subscribe_command(
            cfg.command_topic, GimbalCmd, parse=parse_gimbal_cmd
        )
        self._imu = LatestMessage()
        self._odom = LatestMessage()
        self.subscribe(cfg.imu_topic, Imu, self._imu.put, qos_profile_sensor_data)
        self.subscribe(cfg.odom_topic, Odometry, self._odom.put, qos_profile_sensor_data)
        self._gimbal_state_pub = self.create_publisher(GimbalState, cfg.state_topic, 10)
        self._imu_topic = self.node.resolve_topic_name(cfg.imu_topic)
        self._odom_topic = self.node.resolve_topic_name(cfg.odom_topic)
        self._yaw_loop = AxisLoop(cfg.yaw.angle_pid, cfg.yaw.max_joint_velocity)
        self._pitch_loop = AxisLoop(cfg.pitch.angle_pid, cfg.pitch.max_joint_velocity)
        self._yaw_base_rate = Smoother(cfg.base_rate_tau)
        self._pitch_base_rate = Smoother(cfg.base_rate_tau)
        self._base_pitch = Smoother(cfg.base_rate_tau)
        # Yaw of the odom frame in the IMU's world frame; 0 until odometry is seen.
        self._odom_offset = Smoother(cfg.odom_alignment_tau, angle=True)
        self._state_period_ns = round(_NS_PER_S / cfg.state_rate)
        self._next_state_ns = 0
        self._joint_frames = self.create_frame_publisher()
        self._frames_period_ns = round(_NS_PER_S / cfg.frames.rate)
        self._next_frames_ns = 0
        self.create_frame_publisher(static=True).send(
            mount_links(cfg.frames), self.node.get_clock().now().nanoseconds
        )
        # A TRACK target in another frame of the tree, put in odom (or base_link) once per
        # command, with the transforms of the moment it arrived: (command, frame, point).
        self._placed: tuple[GimbalRequest, str, tuple[float, float, float]] | None = None
        self._published_mode: GimbalMode | None = None
        self.on_reset()

    def on_reset(self) -> None:
        """Forget targets, integrators and filters (enable, disable, command lost)."""
        self._yaw_target: float | None = None
        self._pitch_target: float | None = None
        self._active_mode = GimbalMode.PASSIVE
        self._yaw_loop.reset()
        self._pitch_loop.reset()
        for smoother in (
            self._yaw_base_rate,
            self._pitch_base_rate,
            self._base_pitch,
        ):
            smoother.reset()

    # -- tick -------------------------------------------------------------------------------

    def update(self, now: Time, dt: float) -> None:
        """Decide the state, run the loops, send both joints' targets, publish the state."""
        now_ns = now.nanoseconds
        if not dt > 0.0:
            return
        self._send_frames(now_ns)
        cmd: GimbalRequest | None = self.command.latest(now_ns)
        measurement = self._measure(now_ns)
        odom = self._odom_pose(now_ns)
        if isinstance(measurement, Measurement) and not isinstance(odom, str):
            # Follow the yaw of the odom frame in the IMU's world frame (drift, start-up).
            self._odom_offset.update(wrap_to_pi(measurement.base_yaw - odom.pose.yaw), dt)
        mode, reason, aim = self._decide(cmd, measurement, odom)
        self.transition(mode, reason)
        if mode is GimbalMode.PASSIVE or cmd is None or not isinstance(measurement, Measurement):
            self._go_limp()
        else:
            self._control(mode, cmd, measurement, aim, dt)
        self._publish_state(now, measurement)

    def on_config(self, config: GimbalTuning) -> None:
        """Gains and limits set while running: the angle loops restart with them."""
        self.config = cfg = with_tuning(self.config, config)
        self._yaw_loop = AxisLoop(cfg.yaw.angle_pid, cfg.yaw.max_joint_velocity)
        self._pitch_loop = AxisLoop(cfg.pitch.angle_pid, cfg.pitch.max_joint_velocity)

    def on_command_lost(self, now: Time, dt: float) -> None:
        """No command: joints off (the framework is already in PASSIVE with the reason)."""
        self._send_frames(now.nanoseconds)
        self._go_limp()
        self._publish_state(now, self._measure(now.nanoseconds))

    def _go_limp(self) -> None:
        self.zero_output()
        if self._active_mode is not GimbalMode.PASSIVE:
            self.on_reset()

    # -- the state machine ------------------------------------------------------------------

    def _decide(
        self,
        cmd: GimbalRequest | None,
        measurement: Measurement | str,
        odom: _Odom | str,
    ) -> tuple[GimbalMode, str, _Aim | None]:
        """The one place that chooses the state: (state, reason, TRACK aim or None)."""
        if cmd is None:
            return GimbalMode.PASSIVE, 'no command', None
        if cmd.mode is GimbalMode.PASSIVE:
            return GimbalMode.PASSIVE, 'commanded', None
        if isinstance(measurement, str):
            return GimbalMode.PASSIVE, measurement, None
        if cmd.mode is GimbalMode.RATE:
            return GimbalMode.RATE, 'rates held in the world frame', None
        return self._decide_track(cmd, measurement, odom)

    def _decide_track(
        self, cmd: GimbalRequest, m: Measurement, odom: _Odom | str
    ) -> tuple[GimbalMode, str, _Aim | None]:
        cfg = self.config
        frame, target = cmd.frame, cmd.target
        px, py, pz = cfg.pivot
        if frame not in cfg.base_frames and frame not in cfg.world_frames:
            placed = self._place(cmd, frame, target)
            if isinstance(placed, str):
                return GimbalMode.PASSIVE, f'rejected command: {placed}', None
            frame, target = placed
        if frame in cfg.base_frames:
            origin = cfg.pivot
        else:  # a world frame (a placed target is in one of the two)
            if isinstance(odom, str):
                return GimbalMode.TRACK, f'holding the aim: {odom}', None
            pivot_x, pivot_y = odom.pose.to_world(px, py)
            origin = (pivot_x, pivot_y, odom.z + pz)
        aim, in_range = self._solve(origin, target, cmd.bullet_speed)
        if aim is None or aim.distance < cfg.min_track_distance:
            return (
                GimbalMode.TRACK,
                f'holding the aim: target within {cfg.min_track_distance} m of the yaw axis',
                None,
            )
        if frame in cfg.base_frames:
            # A point fixed to the chassis turns with it: the chassis' rate is the feed-forward.
            yaw_target, rates, follows_base = m.base_yaw + aim.yaw, (0.0, 0.0), True
        else:
            # A point fixed in odom: the line of sight turns as the pivot moves.
            assert not isinstance(odom, str)  # world frames without odometry returned above
            yaw_target = aim.yaw + (self._odom_offset.value or 0.0)
            vx, vy = odom.pose.velocity_of(px, py, odom.vx, odom.vy, odom.wz)
            offset = (target[0] - origin[0], target[1] - origin[1], target[2] - origin[2])
            rates, follows_base = sight_rates(offset, (-vx, -vy, 0.0)), False
        reason = f'tracking a point in {frame}'
        if not in_range:
            reason += ': out of range at the bullet speed, aiming along the line of sight'
        return (
            GimbalMode.TRACK,
            reason,
            _Aim(wrap_to_pi(yaw_target), aim.pitch, *rates, follows_base=follows_base),
        )

    def _place(
        self, cmd: GimbalRequest, frame: str, point: tuple[float, float, float]
    ) -> tuple[str, tuple[float, float, float]] | str:
        """A point given in another frame of the TF tree, in odom (else base_link).

        Done once per command, with the transforms of the moment it is first seen (as a
        detection is true at its stamp): re-placing it every run would move a point given
        in a frame that turns with the gimbal (the camera) as the gimbal turns to it.
        Returns the frame and point, or why it cannot be placed.
        """
        placed = self._placed
        if placed is not None and placed[0] is cmd:
            return placed[1], placed[2]
        self._send_frames(self.node.get_clock().now().nanoseconds, force=True)
        cfg = self.config
        tree = self.frames.frames()
        if frame.lstrip('/') not in tree:
            known = dict.fromkeys((*cfg.world_frames, *cfg.base_frames, *sorted(tree)))
            return f'unknown target frame {frame!r} (known: {", ".join(known)})'
        problem = ''
        for into in (cfg.world_frames[0], cfg.base_frames[0]) if cfg.world_frames else (
            cfg.base_frames[0],
        ):
            try:
                found = self.frames.lookup(into, frame)
            except FrameLookupError as err:
                problem = str(err)
                continue
            x, y, z = (float(v) for v in found.transform.apply(point))
            self._placed = (cmd, into, (x, y, z))
            return into, (x, y, z)
        return f'target frame {frame!r}: {problem}'

    def _send_frames(self, now_ns: int, *, force: bool = False) -> None:
        """Send base -> yaw -> pitch at the joints' angles, every frames.rate (or now)."""
        if now_ns < self._next_frames_ns and not force:
            return
        cfg = self.config
        angles = []
        for name in (cfg.yaw.joint, cfg.pitch.joint):
            state = self.joint_states.get(name)
            if state is None or not math.isfinite(state.position):
                return
            angles.append(state.position)
        self._next_frames_ns = now_ns + self._frames_period_ns
        self._joint_frames.send(joint_links(cfg.frames, cfg.pivot, *angles), now_ns)

    def _solve(
        self, origin: tuple[float, float, float], target: tuple[float, float, float], speed: float
    ) -> tuple[AimSolution | None, bool]:
        """Aim from origin at target (rm_base.geometry.aim); return (aim, in range).

        The aim is None when the target is straight above or below the pivot. Out of range
        at the bullet speed, it is the line of sight.
        """
        line_of_sight = aim_from_point(origin, target)
        if line_of_sight is None or speed <= 0.0:
            return line_of_sight, True
        ballistic = aim_from_point(
            origin,
            target,
            bullet_speed=speed,
            model=self.config.projectile,
            barrel_length=self.config.barrel_length,
        )
        if ballistic is None:
            return line_of_sight, False
        return ballistic, True

    # -- control ----------------------------------------------------------------------------

    def _control(
        self, mode: GimbalMode, cmd: GimbalRequest, m: Measurement, aim: _Aim | None, dt: float
    ) -> None:
        cfg = self.config
        held_yaw, held_pitch = self._yaw_target, self._pitch_target
        if self._active_mode is GimbalMode.PASSIVE or held_yaw is None or held_pitch is None:
            # From limp to active: start where the barrel points, with fresh loops.
            self.on_reset()
            held_yaw, held_pitch = m.yaw, m.pitch
        self._active_mode = mode

        yaw_base_rate = self._yaw_base_rate.update(m.yaw_rate - m.yaw_joint_velocity, dt)
        pitch_base_rate = self._pitch_base_rate.update(m.pitch_rate - m.pitch_joint_velocity, dt)
        base_pitch = self._base_pitch.update(m.pitch - m.pitch_joint, dt)

        yaw_rate = cfg.yaw.angle_pid.output_limit
        pitch_rate = cfg.pitch.angle_pid.output_limit
        if mode is GimbalMode.RATE:
            yaw_ff = clamp(cmd.rates[0], -yaw_rate, yaw_rate)
            pitch_ff = clamp(cmd.rates[1], -pitch_rate, pitch_rate)
            # Integrate, but never lead the barrel by more than max_target_lead: a gimbal
            # held back (blocked, or its loop starved) must not wind the target up.
            lead = cfg.max_target_lead
            yaw_target = m.yaw + clamp(wrap_to_pi(held_yaw + yaw_ff * dt - m.yaw), -lead, lead)
            pitch_target = m.pitch + clamp(held_pitch + pitch_ff * dt - m.pitch, -lead, lead)
        elif aim is not None:
            yaw_ff = clamp(
                aim.yaw_rate + (yaw_base_rate if aim.follows_base else 0.0), -yaw_rate, yaw_rate
            )
            pitch_ff = clamp(aim.pitch_rate, -pitch_rate, pitch_rate)
            yaw_target, pitch_target = aim.yaw, aim.pitch
        else:  # TRACK, holding the aim
            yaw_ff = pitch_ff = 0.0
            yaw_target, pitch_target = held_yaw, held_pitch

        # The joint limits, seen in the world: the base may be tilted.
        low, high = cfg.pitch_min + base_pitch, cfg.pitch_max + base_pitch
        if not low <= pitch_target <= high:
            pitch_target = clamp(pitch_target, low, high)
            pitch_ff = 0.0
        self._yaw_target, self._pitch_target = wrap_to_pi(yaw_target), pitch_target

        yaw = self._yaw_loop.update(
            target=yaw_target,
            measured=m.yaw,
            rate_feedforward=yaw_ff,
            base_rate=yaw_base_rate,
            dt=dt,
        )
        pitch = self._pitch_loop.update(
            target=pitch_target,
            measured=m.pitch,
            rate_feedforward=pitch_ff,
            base_rate=pitch_base_rate,
            dt=dt,
            joint_angle=m.pitch_joint,
            joint_limits=(cfg.pitch_min, cfg.pitch_max),
            limit_gain=cfg.limit_gain,
        )
        self.send_joint_targets(
            {
                cfg.yaw.joint: JointTarget.with_velocity(yaw.joint_velocity),
                cfg.pitch.joint: JointTarget.with_velocity(pitch.joint_velocity),
            }
        )

    # -- inputs -----------------------------------------------------------------------------

    def _measure(self, now_ns: int) -> Measurement | str:
        """Return the measurement brought forward to now_ns, or why there is none."""
        cfg = self.config
        sample = self._imu.get()
        if sample is None:
            return f'no IMU data on {self._imu_topic}'
        imu, stamp_ns = sample
        age = (now_ns - stamp_ns) / _NS_PER_S
        if abs(age) > cfg.imu_timeout:
            return f'no IMU data on {self._imu_topic} within {cfg.imu_timeout:.3f} s'
        if imu.orientation_covariance[0] == -1.0:
            return f'IMU on {self._imu_topic} gives no orientation'
        o, w = imu.orientation, imu.angular_velocity
        try:
            roll, pitch, yaw = rpy_from_quaternion((o.x, o.y, o.z, o.w))
        except InputRejectedError as err:
            return f'IMU on {self._imu_topic}: {err}'
        if not (math.isfinite(w.x) and math.isfinite(w.y) and math.isfinite(w.z)):
            return f'IMU on {self._imu_topic}: angular velocity not finite'
        # Body rates -> Euler rates of R = Rz(yaw) Ry(pitch) Rx(roll): the world yaw rate is
        # the z row of R applied to them, (-sin p, cos p sin r, cos p cos r); the pitch rate
        # is cos r * wy - sin r * wz (wy for a level base).
        sr, cr = math.sin(roll), math.cos(roll)
        sp, cp = math.sin(pitch), math.cos(pitch)
        yaw_rate = -sp * w.x + cp * sr * w.y + cp * cr * w.z
        pitch_rate = cr * w.y - sr * w.z
        ahead = max(age, 0.0)
        joints = []
        for name in (cfg.yaw.joint, cfg.pitch.joint):
            state = self.joint_states.get(name)
            if state is None:
                return f'no state of joint {name}'
            if not state.online:
                return f'joint {name} is offline'
            joint_age = (now_ns - state.stamp_ns) / _NS_PER_S
            if abs(joint_age) > cfg.joint_timeout:
                return f'no state of joint {name} within {cfg.joint_timeout:.3f} s'
            if not (math.isfinite(state.position) and math.isfinite(state.velocity)):
                return f'joint {name}: state not finite'
            joints.append((state.position + state.velocity * max(joint_age, 0.0), state.velocity))
        (yaw_joint, yaw_velocity), (pitch_joint, pitch_velocity) = joints
        return Measurement(
            yaw=wrap_to_pi(yaw + yaw_rate * ahead),
            pitch=pitch + pitch_rate * ahead,
            yaw_rate=yaw_rate,
            pitch_rate=pitch_rate,
            yaw_joint=yaw_joint,
            pitch_joint=pitch_joint,
            yaw_joint_velocity=yaw_velocity,
            pitch_joint_velocity=pitch_velocity,
        )

    def _odom_pose(self, now_ns: int) -> _Odom | str:
        """Return the chassis in odom brought forward to now_ns, or why there is none."""
        sample = self._odom.get()
        if sample is None:
            return f'no odometry on {self._odom_topic}'
        odom, stamp_ns = sample
        age = (now_ns - stamp_ns) / _NS_PER_S
        if abs(age) > self.config.odom_timeout:
            return f'no odometry on {self._odom_topic} within {self.config.odom_timeout:.3f} s'
        p, o = odom.pose.pose.position, odom.pose.pose.orientation
        v, w = odom.twist.twist.linear, odom.twist.twist.angular
        try:
            yaw = yaw_from_quaternion((o.x, o.y, o.z, o.w))
        except InputRejectedError as err:
            return f'odometry on {self._odom_topic}: {err}'
        values = (p.x, p.y, p.z, v.x, v.y, w.z)
        if not all(map(math.isfinite, values)):
            return f'odometry on {self._odom_topic} is not finite'
        pose = PlanarPose(p.x, p.y, yaw).extrapolated(v.x, v.y, w.z, max(age, 0.0))
        return _Odom(pose, p.z, v.x, v.y, w.z)

    # -- output -----------------------------------------------------------------------------

    def _publish_state(self, now: Time, measurement: Measurement | str) -> None:
        now_ns = now.nanoseconds
        mode = GimbalMode(self.state.value)
        if now_ns < self._next_state_ns and mode is self._published_mode:
            return
        if not self.heard(self._gimbal_state_pub):
            return
        self._next_state_ns = now_ns + self._state_period_ns
        self._published_mode = mode
        offset = self._odom_offset.value or 0.0
        nan = math.nan
        if isinstance(measurement, Measurement):
            angles = (
                wrap_to_pi(measurement.yaw - offset), measurement.pitch,
                measurement.yaw_joint, measurement.pitch_joint,
            )
        else:
            angles = (nan, nan, nan, nan)
        yaw_target, pitch_target = self._yaw_target, self._pitch_target
        if mode is GimbalMode.PASSIVE or yaw_target is None or pitch_target is None:
            targets = (nan, nan)
        else:
            targets = (wrap_to_pi(yaw_target - offset), pitch_target)
        # built by the ROS edge's thread, from these values
        self.publish_built(
            self._gimbal_state_pub, _gimbal_state_message, now_ns,
            self.config.world_frames[0], int(mode), self.reason, angles + targets,
        )


def _gimbal_state_message(
    stamp_ns: int, frame_id: str, state: int, reason: str, angles: tuple[float, ...]
) -> GimbalState:
    """/gimbal_state of one report (a new message each call).

    angles: yaw, pitch, yaw_joint, pitch_joint, yaw_target, pitch_target [rad].
    """
    msg = GimbalState()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, _NS_PER_S)
    msg.header.frame_id = frame_id
    msg.state = state
    msg.reason = reason
    (msg.yaw, msg.pitch, msg.yaw_joint, msg.pitch_joint, msg.yaw_target,
     msg.pitch_target) = (float(a) for a in angles)
    return msg
