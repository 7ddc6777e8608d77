"""StandChassis: a mecanum/omni/swerve chassis: PASSIVE, RAW, FOLLOW, TWIST, GYRO and POSITION.

Why one module: one state machine and the tick that runs it; kinematics, planner, odometry,
power and config are modules of their own.

Inputs
    /chassis_cmd (rm_msgs/ChassisCmd): the state, acceleration limits, power limit,
        follow source and speed gear (its ``gears.<gear>`` coefficients scale /vel_cmd's
        vx, vy and wz). Watched: without a command for ``command_timeout`` the framework
        puts the chassis in PASSIVE.
    /vel_cmd (geometry_msgs/Twist): vx, vy [m/s] and (RAW only) wz [rad/s]. Not watched:
        without one for ``vel_cmd_timeout`` the translation brakes to zero on the brake
        ramp, in whatever state the chassis is.
    /actuator_states: wheel speeds and the gimbal yaw joint angle (``yaw_joint``).
    /imu (sensor_msgs/Imu, optional): the odometry yaw, and the gimbal's yaw rate that
        FOLLOW feeds forward.

Outputs
    /actuator_cmd: MODE_VELOCITY on every wheel while active, MODE_OFF in PASSIVE; a
        swerve chassis' steering joints MODE_POSITION (``rm_plugins.chassis.drive``: no
        module turns more than 90°, its wheel reverses instead) and MODE_OFF in PASSIVE.
    /chassis_state (rm_msgs/ChassisState) and /odom (nav_msgs/Odometry, odom -> base_link,
        twist in base_link) at ``publish_rate``; odom -> base_link then on /tf (and in the
        robot's frame tree, ``PluginBase.frames``), unless ``odom.publish_tf`` is false.

States (values = ChassisCmd mode constants), all decided in ``_decide``:
    PASSIVE: commanded; or no valid /chassis_cmd (watchdog); or a wheel or steering joint
        (or, in a mode that follows the gimbal, the yaw joint) without fresh feedback.
        Wheels (and steering joints) get MODE_OFF.
    RAW, FOLLOW, TWIST, GYRO: as commanded, see ``rm_plugins.chassis.modes``.
    POSITION: move by ChassisCmd's (move_x, move_y, move_yaw) from the odometry pose where
        a new move_id began, then hold there (``rm_plugins.chassis.position``); a move_id
        runs once: after a PASSIVE or a silence the same one holds where the chassis
        stands. /vel_cmd is not used, the reason says whether it has arrived.

An invalid /chassis_cmd (unknown mode, follow source or speed gear, NaN) is rejected with a log line
and changes nothing: the chassis keeps acting on the last valid command until that one is
``command_timeout`` old, then falls back to PASSIVE. Staying is safer than an immediate
PASSIVE on a moving robot (limp wheels coast with no braking at all), and a sender that
sends only bad commands still ends in PASSIVE within the timeout.

follow_source: '' (the gimbal) takes the heading from the yaw joint angle; 'base_link'
holds the robot's own heading at the moment the mode was entered, in odom (so FOLLOW
drives straight in the robot frame it had, TWIST swings about it, and GYRO translates in
that fixed world direction while spinning); it is taken anew after any PASSIVE. 'odom'
gives /vel_cmd's vx, vy in the odom frame's own axes (RC10's world speed), in every mode:
in RAW wz is the chassis' own rate, FOLLOW turns the chassis to odom's x axis, GYRO spins
while translating in odom.

The wheel speed loops: the chassis sends wheel *velocity* targets, each wheel's velocity
PID (its joint's ``velocity_pid`` in can_bridge) runs in the 1 kHz loop, and a power-limit
stage of the same tick scales the four efforts by one common factor before they are
packed (``PluginBase.power_limit``; the firmware order: speed loops, then one factor on
the four currents), so the power model sees speeds at most one tick old. With rm_robot as
a process of its own the stage runs in the bridge, which gets it on /power_limit. If the
plugin stalls, the bridge's own command timeout (100 ms) zeroes the wheels.

Odometry (``odometry``) counts the wheels' angle changes, so late ticks lose no distance;
its yaw comes from the IMU when one is configured and fresh (minus the yaw joint angle
when it sits on the gimbal), from the wheels otherwise.

GYRO's spin is closed on that yaw (``gyro.heading.*``, ``rm_plugins.chassis.spin_heading``):
a wheel that drags or slips does not slow the spin, the other wheels are asked for more.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry as OdometryMsg
from rclpy.qos import qos_profile_sensor_data
from rclpy.time import Time
from rm_base.control import estimate_power
from rm_base.errors import InputRejectedError
from rm_base.geometry import (
    SE3,
    SwerveKinematics,
    Twist2D,
    quaternion_from_yaw,
    wrap_to_pi,
    yaw_from_quaternion,
)
from rm_base.hardware.supercap import PowerSupply
from rm_base.joints import JointState
from rm_base.plugin import JointTarget, LatestMessage, LogThrottle, PluginBase, PluginConfigError
from rm_base.plugin.commands import stamp_ns_of
from sensor_msgs.msg import Imu

from rm_msgs.msg import ChassisCmd, ChassisState, RefereePowerHeat, RefereeRobotStatus
from rm_plugins.chassis.commands import (
    ChassisMode,
    ChassisRequest,
    FollowSource,
    SpeedGear,
    parse_chassis_cmd,
    parse_vel_cmd,
)
from rm_plugins.chassis.config import (
    ChassisConfig,
    ChassisTuning,
    ImuMount,
    read_config,
    with_tuning,
)
from rm_plugins.chassis.drive import Drive, SwerveDrive
from rm_plugins.chassis.modes import ChassisMotionMode
from rm_plugins.chassis.motion import (
    BASE_LINK_FRAME,
    GIMBAL_FRAME,
    ODOM_FRAME,
    CommandFrame,
    MotionPlanner,
    held_frame,
)
from rm_plugins.chassis.odometry import Odometry, Pose2D
from rm_plugins.chassis.position import Goal, goal_of, position_command
from rm_plugins.chassis.referee_power import RefereePower

_NS_PER_S = 1_000_000_000
_LOG_PERIOD_NS = _NS_PER_S  # at most one line per second per kind of rejected input
# Largest time over which the yaw joint angle is extrapolated to now with its velocity [s].
_MAX_EXTRAPOLATION_S = 0.05

# Wheel feedback gap [s] after which the odometry checks for a restart of the encoders'
# multi-turn count (a bridge restart takes longer than this).
_ODOM_GAP_S = 0.5

# Largest time between an IMU sample and the yaw joint sample combined into a chassis yaw [s]
# (a few feedback periods).
_MAX_IMU_JOINT_SKEW_S = 0.02

_MOTION_MODES = {
    ChassisMode.RAW: ChassisMotionMode.RAW,
    ChassisMode.FOLLOW: ChassisMotionMode.FOLLOW,
    ChassisMode.TWIST: ChassisMotionMode.TWIST,
    ChassisMode.GYRO: ChassisMotionMode.GYRO,
    ChassisMode.POSITION: ChassisMotionMode.RAW,  # a velocity in odom toward the goal
}

# Odometry covariances (diagonal, x y z roll pitch yaw): planar, so z/roll/pitch are
# "unknown" (large). Wheel odometry drifts; these are typical for mecanum on carpet.
_POSE_COVARIANCE = (1e-3, 1e-3, 1e6, 1e6, 1e6, 1e-2)
_TWIST_COVARIANCE = (1e-3, 1e-3, 1e6, 1e6, 1e6, 1e-2)


class _Decision(NamedTuple):
    """The state for this tick, why, and the request to act on (None in PASSIVE)."""

    state: ChassisMode
    reason: str
    request: ChassisRequest | None
    yaw_joint: JointState | None = None  # when following the gimbal


class StandChassis(PluginBase):
    """Mecanum/omni/swerve chassis; see the module docstring. Parameters: ``config.read_config``."""

    State = ChassisMode
    config: ChassisConfig

    # -- hooks --------------------------------------------------------------------------

    def on_init(self) -> None:
        """Read the parameters, claim the wheels, subscribe, create publishers."""
        cfg: ChassisConfig = read_config(self.params, self.read_config(ChassisTuning))
        self.config = cfg
        self.claim_joints(cfg.wheel_joints + cfg.steer_joints)
        # swerve: the steering targets and angles live between ticks in the drive
        self._swerve: SwerveDrive | None = None
        self._drive: Drive
        if isinstance(cfg.wheels, SwerveKinematics):
            self._drive = self._swerve = SwerveDrive(cfg.wheels)
        else:
            self._drive = cfg.wheels
        self._chassis_cmd = self.subscribe_command(
            'chassis_cmd', ChassisCmd, parse=parse_chassis_cmd
        )
        self._vel_cmd = self.subscribe_command(
            'vel_cmd', Twist, timeout=cfg.vel_cmd_timeout, watchdog=False, parse=parse_vel_cmd
        )
        self._planner = MotionPlanner(
            self._drive, cfg.modes, cfg.linear_limits, cfg.angular_limits, cfg.max_wheel_speed
        )
        # The wheels' own 1 kHz loops and a power stage after them, in the loop that drives
        # them (this process's, or the bridge's when rm_robot runs alone).
        self._power_stage = self.power_limit(cfg.wheel_joints, cfg.power_model)
        if self._power_stage is None:
            raise PluginConfigError('no control loop runs the wheels (no power stage)')
        self._referee_power: RefereePower | None = None
        if cfg.referee_power is not None:
            self._referee_power = referee = RefereePower(cfg.referee_power, cfg.referee_timeout)
            self.subscribe('referee/robot_status', RefereeRobotStatus, referee.on_robot_status, 10)
            self.subscribe('referee/power_heat', RefereePowerHeat, referee.on_power_heat, 10)
        self._odometry = Odometry(self._drive)
        self._imu = LatestMessage(use_stamp=False)
        if cfg.imu_mount is not ImuMount.NONE:
            # Sensor QoS (best effort, keep last): an old IMU sample is worthless.
            self.subscribe(cfg.imu_topic, Imu, self._imu.put, qos_profile_sensor_data)
        self._chassis_state_pub = self.create_publisher(ChassisState, 'chassis_state', 10)
        self._odom_pub = self.create_publisher(OdometryMsg, 'odom', 10)
        self._tf = self.create_frame_publisher() if cfg.publish_tf else None
        self._publish_period_ns = round(_NS_PER_S / cfg.publish_rate)
        self._next_publish_ns = 0
        self._last_odom_ns: int | None = None
        self._imu_used_ns: int | None = None
        self._throttles = {'imu': LogThrottle(_LOG_PERIOD_NS)}
        self._report = _Report(len(cfg.wheel_joints))
        # the last POSITION move started: kept across resets, so a move runs once
        self._started_move_id: int | None = None
        self.on_reset()

    def on_config(self, config: ChassisTuning) -> None:
        """Live values set while running: gears and limit read at use, the rest handed on."""
        self.config = cfg = with_tuning(self.config, config)
        self._planner.set_default_limits(cfg.linear_limits, cfg.angular_limits)
        self._planner.set_mode_params(cfg.modes)
        self._power_stage.model = cfg.power_model

    def on_reset(self) -> None:
        """Forget commands, ramps and PIDs (not the odometry: the pose stays continuous)."""
        # Commands: never act on one from before the reset (the framework clears inputs).
        self._request: ChassisRequest | None = None
        # Control: restarted from the measured motion when a motion state is entered.
        self._active = False
        self._held_heading: float | None = None
        self._goal: Goal | None = None  # POSITION: the move's goal in odom
        self._move_id = 0
        self._planner.reset()

    def update(self, now: Time, dt: float) -> None:
        """One tick: feedback and odometry, the state, then the wheels and the reports."""
        now_ns = now.nanoseconds
        wheels, wheel_problem = self._wheel_states(now_ns)
        self._update_odometry(now_ns, wheels)
        speeds = None if wheels is None else [w.velocity for w in wheels]
        decision = self._decide(now_ns, wheel_problem)
        if decision.request is None or speeds is None:
            self._passive(now_ns, decision.state, decision.reason, speeds)
        else:
            self._drive_wheels(now_ns, dt, decision, decision.request, speeds)
        self._maybe_publish(now)

    def on_command_lost(self, now: Time, dt: float) -> None:
        """Zero output while /chassis_cmd is missing; odometry and reports go on."""
        # The framework has gone to PASSIVE with the watchdog's reason and reset us.
        now_ns = now.nanoseconds
        wheels, _ = self._wheel_states(now_ns)
        self._update_odometry(now_ns, wheels)
        self._passive(now_ns, None, '', None if wheels is None else [w.velocity for w in wheels])
        self._maybe_publish(now)

    # -- commands -----------------------------------------------------------------------

    def _take_vel_cmd(self, now_ns: int) -> tuple[float, float, float]:
        # without one within vel_cmd_timeout: brake to a stop on the ramp, not PASSIVE
        vel: tuple[float, float, float] | None = self._vel_cmd.latest(now_ns)
        return (0.0, 0.0, 0.0) if vel is None else vel

    def _decide(self, now_ns: int, wheel_problem: str | None) -> _Decision:
        """Return the state, its reason, and the request to act on (None: PASSIVE)."""
        request: ChassisRequest | None = self._chassis_cmd.latest(now_ns)
        self._request = request
        if request is None:
            return _Decision(
                ChassisMode.PASSIVE, 'no valid /chassis_cmd within command_timeout', None
            )
        if request.mode is ChassisMode.PASSIVE:
            return _Decision(ChassisMode.PASSIVE, 'commanded PASSIVE', None)
        if wheel_problem is not None:
            return _Decision(ChassisMode.PASSIVE, wheel_problem, None)
        yaw_joint = None
        # POSITION moves in odom, RAW in base_link: neither needs the gimbal's heading
        follows_gimbal = request.mode not in (ChassisMode.RAW, ChassisMode.POSITION)
        if follows_gimbal and request.source is FollowSource.GIMBAL:
            # Read once: the view may change under us (a newer message, maybe offline).
            yaw_joint = self._yaw_joint_state(now_ns)
            if yaw_joint is None:
                return _Decision(
                    ChassisMode.PASSIVE,
                    f"{request.mode.name} needs the gimbal heading, but yaw joint "
                    f"'{self.config.yaw_joint}' has no fresh feedback",
                    None,
                )
        reason = f'commanded {request.mode.name}'
        if request.gear is not SpeedGear.NORMAL:
            reason += f' in {request.gear.name} gear'
        if request.source is FollowSource.ODOM or (
            request.mode is not ChassisMode.RAW and request.source is FollowSource.BASE_LINK
        ):
            reason += f' (follow source {request.source.value})'
        return _Decision(request.mode, reason, request, yaw_joint)

    # -- feedback -----------------------------------------------------------------------

    def _fresh(self, joint: str, now_ns: int) -> JointState | None:
        state = self.joint_states.get(joint)
        timeout_ns = self.config.wheel_feedback_timeout * _NS_PER_S
        if state is None or not state.online or now_ns - state.stamp_ns > timeout_ns:
            return None
        return state

    def _wheel_states(self, now_ns: int) -> tuple[list[JointState] | None, str | None]:
        """The wheels' states; a swerve chassis' steering angles go to its drive."""
        states = []
        for joint in self.config.wheel_joints:
            state = self._fresh(joint, now_ns)
            if state is None:
                return None, f"wheel '{joint}' has no fresh feedback (offline or stale)"
            states.append(state)
        if self._swerve is not None:
            angles = []
            for joint in self.config.steer_joints:
                state = self._fresh(joint, now_ns)
                if state is None:
                    return None, (
                        f"steering joint '{joint}' has no fresh feedback (offline or stale)"
                    )
                angles.append(state.position)
            self._swerve.observe(angles)
        return states, None

    def _yaw_joint_state(self, now_ns: int) -> JointState | None:
        return self._fresh(self.config.yaw_joint, now_ns)

    def _imu_sample(self, now_ns: int) -> tuple[Any, int] | None:
        """Return the newest IMU message and its stamp [ns] if fresh and usable."""
        sample = self._imu.get()
        if sample is None:
            return None
        msg, receive_ns = sample
        stamp_ns = stamp_ns_of(msg) or receive_ns
        if abs(now_ns - stamp_ns) > self.config.imu_timeout * _NS_PER_S:
            return None
        if msg.orientation_covariance[0] == -1.0:  # REP 145: no orientation estimate
            return None
        return msg, stamp_ns

    def _imu_chassis_yaw(self, now_ns: int) -> float | None:
        """Chassis yaw from the IMU (any reference heading) [rad], or None."""
        sample = self._imu_sample(now_ns)
        if sample is None:
            return None
        msg, stamp_ns = sample
        q = msg.orientation
        try:
            yaw = yaw_from_quaternion((q.x, q.y, q.z, q.w))
        except InputRejectedError as err:
            more = self._throttles['imu'].due(now_ns)
            if more is not None:
                self.logger.warning(f'ignored /imu orientation: {err}{more}')
            return None
        if self.config.imu_mount is ImuMount.CHASSIS:
            return yaw
        joint = self._yaw_joint_state(now_ns)
        if joint is None:
            return None
        # The joint angle at the IMU's sample time: at 8 rad/s of spin 5 ms is 0.04 rad.
        # Samples further apart (a stall on either side) are not combined: a bad pair would
        # become a lasting offset when the odometry (re)takes the IMU as its reference.
        lag_s = (stamp_ns - joint.stamp_ns) / _NS_PER_S
        if abs(lag_s) > _MAX_IMU_JOINT_SKEW_S:
            return None
        return yaw - (joint.position - self.config.yaw_zero + joint.velocity * lag_s)

    def _gimbal_world_yaw_rate(self, now_ns: int, phi_rate: float) -> float:
        """Yaw rate of the gimbal in the world [rad/s] (FOLLOW's feed-forward)."""
        sample = self._imu_sample(now_ns) if self.config.imu_mount is ImuMount.GIMBAL else None
        if sample is not None:
            msg = sample[0]
            q, w = msg.orientation, msg.angular_velocity
            # z row of the body -> world rotation: the world z part of the body rate.
            return float(
                2.0 * (q.x * q.z - q.w * q.y) * w.x
                + 2.0 * (q.y * q.z + q.w * q.x) * w.y
                + (1.0 - 2.0 * (q.x * q.x + q.y * q.y)) * w.z
            )
        return self._odometry.twist.wz + phi_rate

    def _update_odometry(self, now_ns: int, wheels: Sequence[JointState] | None) -> None:
        """Move the odometry by the wheel angles since the last update (IMU yaw if fresh)."""
        if wheels is None:
            return  # no wheel feedback: hold the pose; the angles count on meanwhile
        stamp_ns = max(w.stamp_ns for w in wheels)
        last, self._last_odom_ns = self._last_odom_ns, stamp_ns
        reference = self._odometry.wheel_angles
        gap_s = (stamp_ns - last) / _NS_PER_S if last is not None else 0.0
        if reference is not None and gap_s > _ODOM_GAP_S:
            # After a long gap the bridge may have restarted, its multi-turn count with it:
            # a change further than the wheels can turn in the gap (twice the top speed,
            # plus a radian) is that, not motion. Anything else counts, so a stall, however
            # long, loses no distance.
            reach = 2.0 * self.config.max_wheel_speed * gap_s + 1.0
            if any(abs(w.position - a) > reach for w, a in zip(wheels, reference, strict=True)):
                self._odometry.restart_wheel_reference()
                self.logger.warning(
                    f'wheel angles jumped after {gap_s:.2f} s without feedback (bridge '
                    'restarted?): odometry keeps its pose and takes them as a new reference'
                )
        yaw = None if self.config.imu_mount is ImuMount.NONE else self._imu_chassis_yaw(now_ns)
        if yaw is not None:
            self._imu_used_ns = now_ns
        elif (self._imu_used_ns is not None and now_ns - self._imu_used_ns
              > self.config.imu_reference_timeout * _NS_PER_S):
            # Gone for long: it may come back with another reference (a restart).
            self._odometry.release_absolute_yaw()
            self._imu_used_ns = None
        self._odometry.update([w.position for w in wheels], [w.velocity for w in wheels], yaw)

    # -- actuation ----------------------------------------------------------------------

    def _passive(
        self, now_ns: int, state: ChassisMode | None, reason: str, speeds: list[float] | None
    ) -> None:
        if state is not None:
            self.transition(state, reason)
        self.zero_output()
        if self._active:
            self._active = False
            self._held_heading = None
            self._goal = None  # a move interrupted by PASSIVE is over
            if self._swerve is not None:
                self._swerve.reset()  # limp modules may be turned by hand meanwhile
        count = len(self.config.wheel_joints)
        self._report.set_output(
            Twist2D(), [0.0] * count, [0.0] * count,
            self._idle_power(speeds),
            self._set_power(now_ns, self._request),
        )
        self._report.speeds = speeds

    def _set_power(self, now_ns: int, request: ChassisRequest | None) -> float:
        """Hand the power stage this tick's limit and the referee's numbers; the limit.

        A super-capacitor, if the loop has one for the wheels, turns them into its own
        allowance (rm_base.hardware.supercap); without one the limit is the allowance.
        """
        limit = self._power_limit(now_ns, request)
        stage = self._power_stage
        stage.limit_w = limit
        referee_w, buffer_j = (self._referee_power.heard(now_ns)
                               if self._referee_power is not None else (math.nan, math.nan))
        commanded = request.power_limit if request is not None else None
        supply = PowerSupply(referee_w, buffer_j, commanded or 0.0)
        if supply != stage.supply:
            stage.supply = supply
        return limit

    def _power_limit(self, now_ns: int, request: ChassisRequest | None) -> float:
        """The power limit for this tick [W].

        The referee's budget (if heard), else the default; a commanded limit replaces the
        default, and can only lower the referee's.
        """
        commanded = request.power_limit if request is not None else None
        if self._referee_power is None:
            return self.config.power_limit if commanded is None else commanded
        budget = self._referee_power.budget(now_ns, self.config.power_limit)
        return budget if commanded is None else min(budget, commanded)

    def _idle_power(self, speeds: list[float] | None) -> float:
        """Predicted chassis power with no effort at the measured speeds [W]."""
        if speeds is None:
            return 0.0
        return estimate_power(self.config.power_model, [0.0] * len(speeds), speeds)

    def _drive_wheels(
        self,
        now_ns: int,
        dt: float,
        decision: _Decision,
        request: ChassisRequest,
        speeds: list[float],
    ) -> None:
        if request.mode is ChassisMode.POSITION:
            command, arrived = self._move(request)
            where = 'arrived, holding' if arrived else 'moving to the goal'
            self.transition(decision.state, f'{decision.reason}: {where}')
        else:
            self._goal = None  # entering POSITION again starts a new move
            self.transition(decision.state, decision.reason)
            vx, vy, wz = self._take_vel_cmd(now_ns)
            linear, angular = self.config.gears[request.gear]
            command = (vx * linear, vy * linear, wz * angular)
        if not self._active:
            # Take over from the measured motion (the chassis may still be rolling).
            self._planner.reset(self._odometry.twist)
            self._active = True
        mode = _MOTION_MODES[request.mode]
        if request.source is FollowSource.ODOM or request.mode is ChassisMode.POSITION:
            self._held_heading = None
            frame: CommandFrame = ODOM_FRAME
            phi = wrap_to_pi(-self._odometry.pose.yaw)
            phi_rate = -self._odometry.twist.wz
            gimbal_rate = 0.0
        elif mode is ChassisMotionMode.RAW:
            self._held_heading = None
            frame = BASE_LINK_FRAME
            phi = phi_rate = gimbal_rate = 0.0
        elif request.source is FollowSource.GIMBAL:
            self._held_heading = None
            joint = decision.yaw_joint
            assert joint is not None  # _decide stays PASSIVE without fresh yaw feedback
            frame = GIMBAL_FRAME
            # The angle now, not when it was measured: in GYRO it changes at the spin rate,
            # and the feedback is up to a publish period (plus transport) old.
            age_s = min(_MAX_EXTRAPOLATION_S, max(0.0, (now_ns - joint.stamp_ns) / _NS_PER_S))
            phi = wrap_to_pi(joint.position - self.config.yaw_zero + joint.velocity * age_s)
            phi_rate = joint.velocity
            gimbal_rate = self._gimbal_world_yaw_rate(now_ns, phi_rate)
        else:
            yaw = self._odometry.pose.yaw
            if self._held_heading is None:
                self._held_heading = yaw  # the robot's heading now is the one to follow
            frame = held_frame(self._held_heading)
            phi = wrap_to_pi(self._held_heading - yaw)
            phi_rate = -self._odometry.twist.wz
            gimbal_rate = 0.0
        motion = self._planner.update(
            mode, frame, command, dt, accel=request.accel,
            yaw_joint=phi, yaw_joint_rate=phi_rate, gimbal_yaw_rate=gimbal_rate,
            heading=self._odometry.pose.yaw,
        )
        limit = self._set_power(now_ns, request)
        joints = self.config.wheel_joints
        stage = self._power_stage
        targets = {
            joint: JointTarget.with_velocity(target)
            for joint, target in zip(joints, motion.wheel_targets, strict=True)
        }
        if self._swerve is not None:
            for name, angle in zip(
                self.config.steer_joints, self._swerve.steer_targets, strict=True
            ):
                targets[name] = JointTarget.with_position(angle)
        self.send_joint_targets(targets)
        last = stage.last  # the loop's latest tick
        efforts = last.torques if last is not None else (0.0,) * len(joints)
        power_w = last.power_w if last is not None else self._idle_power(speeds)
        self._report.set_output(motion.twist, motion.wheel_targets, efforts, power_w, limit)
        self._report.speeds = speeds

    def _move(self, request: ChassisRequest) -> tuple[tuple[float, float, float], bool]:
        """POSITION: the odom velocity toward this move's goal, and whether it arrived."""
        pose = self._odometry.pose
        if self._goal is None or request.move_id != self._move_id:
            # A move_id that already ran (a PASSIVE blip, a timeout, another mode between)
            # is that move, over: hold where the chassis stands instead of driving it again.
            again = request.move_id == self._started_move_id
            self._goal = goal_of(pose.x, pose.y, pose.yaw, (0.0, 0.0, 0.0) if again
                                 else request.move)
            self._move_id = self._started_move_id = request.move_id
        cfg = self.config
        linear = request.accel[0] or cfg.linear_limits.brake_acceleration
        angular = request.accel[2] or cfg.angular_limits.brake_acceleration
        return position_command(
            (pose.x, pose.y, pose.yaw), self._goal, cfg.position, (linear, angular)
        )

    # -- reports ------------------------------------------------------------------------

    def _maybe_publish(self, now: Time) -> None:
        now_ns = now.nanoseconds
        if now_ns < self._next_publish_ns:
            return
        self._next_publish_ns = max(self._next_publish_ns + self._publish_period_ns, now_ns)
        cfg, report = self.config, self._report
        pose, twist = self._odometry.pose, self._odometry.twist
        # The messages are built by the ROS edge's thread, from these values.
        if self.heard(self._chassis_state_pub):
            speeds = tuple(report.speeds) if report.speeds is not None else None
            request = self._request
            gear = (request.gear if request is not None and self.state is not ChassisMode.PASSIVE
                    else SpeedGear.NORMAL)
            snapshot = _StateReport(
                now_ns, int(self.state.value), self.reason, report.twist, twist,
                tuple(report.targets), speeds, report.power_w, report.power_limit_w, int(gear),
            )
            self.publish_built(self._chassis_state_pub, _chassis_state_message, cfg, snapshot)
        if self.heard(self._odom_pub):
            self.publish_built(self._odom_pub, _odometry_message, cfg, now_ns, pose, twist)
        if self._tf is not None:
            q = quaternion_from_yaw(pose.yaw)
            base = SE3.from_translation_quaternion((pose.x, pose.y, 0.0), q)
            self._tf.send([(cfg.odom_frame, cfg.base_frame, base)], now_ns)


class _Report:
    """What the last tick commanded, for /chassis_state."""

    def __init__(self, count: int) -> None:
        self.twist = Twist2D()
        self.targets: Sequence[float] = [0.0] * count
        self.efforts: Sequence[float] = [0.0] * count
        self.speeds: Sequence[float] | None = None
        self.power_w = 0.0
        self.power_limit_w = 0.0

    def set_output(self, twist: Twist2D, targets: Sequence[float], efforts: Sequence[float],
                   power_w: float, power_limit_w: float) -> None:
        self.twist, self.targets, self.efforts = twist, targets, efforts
        self.power_w, self.power_limit_w = power_w, power_limit_w


class _StateReport(NamedTuple):
    """What one /chassis_state says, kept by the loop for the edge's thread."""

    stamp_ns: int
    state: int
    reason: str
    cmd_vel: Twist2D
    measured_vel: Twist2D
    targets: tuple[float, ...]
    speeds: tuple[float, ...] | None
    power_w: float
    power_limit_w: float
    gear: int


def _chassis_state_message(cfg: ChassisConfig, report: _StateReport) -> ChassisState:
    """/chassis_state of one report (built by the edge's thread: a new message each time)."""
    msg = ChassisState()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(report.stamp_ns, _NS_PER_S)
    msg.header.frame_id = cfg.base_frame
    msg.wheel_name = list(cfg.wheel_joints)
    msg.state = report.state
    msg.reason = report.reason
    _set_twist(msg.cmd_vel, report.cmd_vel)
    _set_twist(msg.measured_vel, report.measured_vel)
    msg.wheel_target = [float(v) for v in report.targets]
    msg.wheel_speed = (
        [float(v) for v in report.speeds] if report.speeds is not None
        else [math.nan] * len(cfg.wheel_joints)
    )
    msg.power = float(report.power_w)
    msg.power_limit = float(report.power_limit_w)
    msg.speed_gear = report.gear
    return msg


def _odometry_message(
    cfg: ChassisConfig, stamp_ns: int, pose: Pose2D, twist: Twist2D
) -> OdometryMsg:
    """/odom of one report (built by the edge's thread: a new message each time)."""
    msg = OdometryMsg()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, _NS_PER_S)
    msg.header.frame_id = cfg.odom_frame
    msg.child_frame_id = cfg.base_frame
    position, orientation = msg.pose.pose.position, msg.pose.pose.orientation
    position.x, position.y = float(pose.x), float(pose.y)
    q = quaternion_from_yaw(pose.yaw)
    orientation.x, orientation.y, orientation.z, orientation.w = q.x, q.y, q.z, q.w
    _set_twist(msg.twist.twist, twist)
    for i, value in enumerate(_POSE_COVARIANCE):
        msg.pose.covariance[7 * i] = value
    for i, value in enumerate(_TWIST_COVARIANCE):
        msg.twist.covariance[7 * i] = value
    return msg


def _set_twist(out: Any, twist: Twist2D) -> None:
    out.linear.x = float(twist.vx)
    out.linear.y = float(twist.vy)
    out.angular.z = float(twist.wz)
