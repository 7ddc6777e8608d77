"""StandShooter: friction wheels and a trigger, from /shoot_cmd to shots.

Why one module: one state machine (FEED, FIRE, REVERSE, BLOCK) whose steps share the
trigger's hold and the burst; config and command are modules of their own.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

from rclpy.qos import qos_profile_sensor_data
from rclpy.time import Time
from rm_base.plugin import JointState, JointTarget, PluginBase

from rm_msgs.msg import (
    GpioState,
    RefereePowerHeat,
    RefereeRobotStatus,
    RefereeShot,
    ShootCmd,
    ShooterState,
)
from rm_plugins.shooter.barrel_heat import BarrelHeat
from rm_plugins.shooter.command import ShootCommand, ShooterStage, ShootMode, parse_shoot_cmd
from rm_plugins.shooter.config import ShooterConfig
from rm_plugins.shooter.heat import RefereeHeatInput
from rm_plugins.shooter.jam_detector import JamDetector

COMMAND_TOPIC = 'shoot_cmd'
STATE_TOPIC = 'shooter_state'
GPIO_STATE_TOPIC = 'gpio_state'
STATE_QOS_DEPTH = 10

_NS_PER_S = 1_000_000_000
_LOG_PERIOD_NS = _NS_PER_S  # at most one "rejected command" line a second
_WAIT_FRICTION = 'waiting for the friction wheels to reach speed'
_REFEREE_QOS_DEPTH = 10

S = ShooterStage


class _SwitchInput:
    """Latest value of one named pin from /gpio_state, handed from the executor thread.

    Args:
        pin: the pin's name.
        timeout_ns: a value older than this is unknown [ns].
        logger: told once if /gpio_state does not carry the pin.
    """

    def __init__(self, pin: str, timeout_ns: int, logger: Any) -> None:
        self.pin = pin
        self._timeout_ns = timeout_ns
        self._logger = logger
        self._lock = threading.Lock()
        self._value: bool | None = None
        self._stamp_ns = 0
        self._reported_missing = False

    def handle(self, msg: GpioState, receive_ns: int) -> None:
        """Take one GpioState (executor thread)."""
        names = list(msg.name)
        if self.pin not in names:
            if not self._reported_missing:
                self._reported_missing = True
                self._logger.warning(
                    f'/gpio_state has no pin {self.pin!r} (pins: {", ".join(names) or "none"}); '
                    'the limit switch stays unknown'
                )
            return
        index = names.index(self.pin)
        if index >= len(msg.value):
            return
        with self._lock:
            self._value = msg.value[index] >= 0.5
            self._stamp_ns = receive_ns

    def read(self, now_ns: int) -> bool | None:
        """Return whether the switch is closed, or None if unknown or too old."""
        with self._lock:
            value, stamp_ns = self._value, self._stamp_ns
        if value is None or now_ns - stamp_ns > self._timeout_ns:
            return None
        return value


@dataclass
class _Burst:
    """The burst being fired: shots left (None: continuous) and when the last step began."""

    remaining: int | None
    hz: float
    last_step_ns: int | None = None


class StandShooter(PluginBase):
    """Friction-wheel shooter with a slotted trigger, a ball switch and jam recovery.

    Topics:
        shoot_cmd (rm_msgs/ShootCmd, in, watched): mode PASSIVE/READY/PUSH, bullet speed
            [m/s], rate hz [shots/s], num (0 = continuous while PUSH), burst_id. A new
            burst_id in PUSH starts a burst; the same command repeated never fires again.
            An unknown mode, NaN/inf, speed <= 0 (READY/PUSH) or hz <= 0 (PUSH) is rejected
            and logged; the last valid command stays in force until its own timeout.
        gpio_state (rm_msgs/GpioState, in): the ball switch (``limit_switch``).
        shooter_state (rm_msgs/ShooterState, out): at ``state_rate`` and on every change.

    States (every transition in ``_advance``):
        PASSIVE: all joints off. No valid command, mode PASSIVE, a joint without state, or
            a fault (too many jams in a row: stays until a new burst_id or another mode).
        FEED: friction wheels at the looked-up speed; trigger turning at ``feed_speed``
            (velocity) until the switch reports a ball -> READY.
        READY: trigger holding the position where the ball arrived. A burst (PUSH with a
            new burst_id) -> PUSH.
        PUSH: one slot step (position + 2*pi/slots, the setpoint moving at ``step_speed``
            with that speed as feed-forward) per shot, a step beginning at most
            every 1/hz s and only with every friction wheel at speed (within
            ``friction_tolerance``) and a ball at the switch (none for ``switch_debounce``
            -> FEED). A shot counts
            when the trigger ends its step within ``step_tolerance``. Burst done -> READY.
        BLOCK: jam (trigger effort high and speed low for a while, in FEED or PUSH): the
            trigger turns back ``reverse_angle`` (position) until there or
            ``block_timeout`` -> FEED. The step that jammed is not counted. After
            ``jam_retries`` recoveries in which the trigger never got past the point where
            it jammed (by a shot, or by feeding beyond it), the next jam gives up: PASSIVE
            with ShooterState.fault.
    """

    State = ShooterStage
    config: ShooterConfig
    TRANSITIONS = {  # noqa: RUF012 (read-only table of the framework's)
        S.PASSIVE: (S.FEED,),
        S.FEED: (S.READY, S.BLOCK),
        S.READY: (S.PUSH, S.FEED),
        S.PUSH: (S.READY, S.FEED, S.BLOCK),
        S.BLOCK: (S.FEED,),
    }

    # -- set-up -------------------------------------------------------------------------------

    def on_init(self) -> None:
        """Read the config, claim the joints, subscribe the topics."""
        self.config = self.read_config(ShooterConfig)
        cfg = self.config
        self._trigger = cfg.trigger_joint
        self._joints = self.claim_joints((*cfg.friction_joints, cfg.trigger_joint))
        self._cmd_input = self.subscribe_command(COMMAND_TOPIC, ShootCmd, parse=parse_shoot_cmd)
        self._switch = _SwitchInput(
            cfg.limit_switch, round(cfg.switch_timeout * _NS_PER_S), self.logger
        )
        self.subscribe(GPIO_STATE_TOPIC, GpioState, self._switch.handle, qos_profile_sensor_data)
        self.state_pub = self.create_publisher(ShooterState, STATE_TOPIC, STATE_QOS_DEPTH)
        self._state_period_ns = round(_NS_PER_S / cfg.state_rate)
        self._detector = JamDetector(cfg.jam_detector)
        # The barrel's heat, kept under the referee's limit (kept across resets: it is
        # the barrel's, not the command's)
        barrel = cfg.heat.barrel
        self._heat = BarrelHeat(barrel) if barrel is not None else None
        self._referee = RefereeHeatInput(cfg.heat.calibre, cfg.heat.referee_timeout)
        if self._heat is not None:
            for topic, msg_type, handler in (
                ('referee/robot_status', RefereeRobotStatus, self._referee.on_robot_status),
                ('referee/power_heat', RefereePowerHeat, self._referee.on_power_heat),
                ('referee/shot', RefereeShot, self._referee.on_shot),
            ):
                self.subscribe(topic, msg_type, handler, _REFEREE_QOS_DEPTH)
        # A joint state this old is no state: the bridge stopped publishing (it may come
        # back with the trigger's position counted from a new zero).
        self._joint_timeout_ns = round(
            self.params.double(
                'joint_timeout',
                0.1,
                description='older joint state -> PASSIVE',
                unit='s',
                gt=0.0,
            )
            * _NS_PER_S
        )
        # Kept across resets: a command that returns after a dropout must not start its burst
        # again (only its shots left: on_reset), and a fault holds until a new burst or mode.
        self._shots_fired = 0
        self._last_burst_id: int | None = None
        self._last_mode: ShootMode | None = None
        self._fault = False
        self._fault_reason = ''
        self._next_reject_log_ns = 0
        self._last_published: tuple[object, ...] | None = None
        self._next_publish_ns = 0
        self.on_reset()

    def on_reset(self) -> None:
        """Forget the command, the burst, the trigger's targets and the jam timer.

        A burst in progress is kept aside: the same PUSH coming back after a lost command
        resumes it (an explicit disable or enable forgets it).
        """
        burst: _Burst | None = getattr(self, '_burst', None)
        self._interrupted: tuple[int | None, int | None] | None = (
            (self._last_burst_id, burst.remaining) if burst is not None else None)
        self._burst: _Burst | None = None
        self._jam_count = 0
        self._attempts = 0  # BLOCK recoveries since the trigger last got past a jam
        self._jam_position: float | None = None  # trigger position at the last jam [rad]
        self._hold: float | None = None  # READY/PUSH: trigger position held [rad]
        self._step_target: float | None = None  # PUSH: end of the step in progress [rad]
        self._step_start_ns = 0
        self._no_ball_since_ns: int | None = None  # PUSH: switch open since [ns]
        self._reverse_target = 0.0  # BLOCK [rad]
        self._block_start_ns = 0
        self._detector.reset()
        self._friction_target = [0.0] * len(self.config.friction_joints)
        self._friction_ready = False
        self._speed = 0.0

    def on_config(self, config: ShooterConfig) -> None:
        """Parameters set while running: what the shooter derives from them follows."""
        super().on_config(config)
        self._state_period_ns = round(_NS_PER_S / config.state_rate)
        self._detector = JamDetector(config.jam_detector)  # a jam timer restarts
        barrel = config.heat.barrel
        if self._heat is not None and barrel is not None:
            self._heat.params = barrel  # the heat so far stays

    def on_enable(self) -> None:
        """A fault or an interrupted burst does not survive an explicit disable/enable."""
        self._fault = False
        self._interrupted = None

    def on_disable(self) -> None:
        """A fault or an interrupted burst does not survive an explicit disable/enable."""
        self._fault = False
        self._interrupted = None

    # -- tick ---------------------------------------------------------------------------------

    def update(self, now: Time, dt: float) -> None:
        """Read the command, switch and joints; decide the state; send the targets."""
        now_ns = now.nanoseconds
        command = self._valid_command(now_ns)
        if command is not None:
            self._follow_command(command)
        if self._heat is not None:
            self._referee.apply(self._heat, now_ns)
            if dt > 0.0:
                self._heat.step(dt)
        joints = self.joint_states.snapshot(self._joints)
        self._advance(command, joints, self._switch.read(now_ns), now_ns, dt)
        self._publish_state(now)

    def on_command_lost(self, now: Time, dt: float) -> None:
        """No command: joints off (the framework went PASSIVE); keep reporting the state."""
        self.zero_output()
        self._friction_ready = False
        self._publish_state(now)

    # -- commands -----------------------------------------------------------------------------

    def _valid_command(self, now_ns: int) -> ShootCommand | None:
        """The last valid command still within its timeout (checked once, as it came)."""
        command: ShootCommand | None = self._cmd_input.latest(now_ns)
        return command

    def _follow_command(self, command: ShootCommand) -> None:
        """Track mode changes and new bursts (which also clear a fault)."""
        if command.mode != self._last_mode:
            if self._fault:
                self._fault = False
                self._attempts, self._jam_position = 0, None
                self.logger.info(f'fault cleared: mode changed to {command.mode.name}')
            self._last_mode = command.mode
            if command.mode is not ShootMode.PUSH:
                self._burst = self._interrupted = None  # releasing PUSH ends the burst
        interrupted = self._interrupted
        if (command.mode is ShootMode.PUSH and self._burst is None and interrupted is not None
                and interrupted[0] == command.burst_id):
            self._interrupted = None
            left = interrupted[1]
            self._burst = _Burst(left, min(command.hz, self.config.max_hz))
            self.logger.info(f'burst {command.burst_id} resumed after the lost command: '
                             f'{"continuous" if left is None else f"{left} shot(s) left"}')
        if command.mode is ShootMode.PUSH and command.burst_id != self._last_burst_id:
            self._interrupted = None
            self._last_burst_id = command.burst_id
            if self._fault:
                self._fault = False
                self.logger.info(f'fault cleared: new burst {command.burst_id}')
            hz = min(command.hz, self.config.max_hz)
            if hz < command.hz:
                self.logger.warning(
                    f'burst {command.burst_id}: {command.hz:g} shots/s limited to max_hz '
                    f'{self.config.max_hz:g}'
                )
            self._burst = _Burst(command.num or None, hz)
            self._jam_count = 0
            self._attempts, self._jam_position = 0, None
        if self._burst is not None:
            self._burst.hz = min(command.hz, self.config.max_hz) or self._burst.hz

    # -- the state machine --------------------------------------------------------------------

    def _advance(
        self,
        command: ShootCommand | None,
        joints: Mapping[str, JointState],
        ball: bool | None,
        now_ns: int,
        dt: float,
    ) -> None:
        """Decide the state for this tick and send the joint targets (all transitions)."""
        cfg = self.config
        passive_reason = self._passive_reason(command, joints, now_ns)
        if passive_reason is not None or command is None:  # no command is a passive reason
            self._go_passive(passive_reason or 'no command')
            return
        self._speed = command.speed
        wheel = cfg.wheel_speed(command.speed)
        self._friction_target = [wheel * d for d in cfg.friction_directions]
        self._friction_ready = all(
            abs(joints[j].velocity - target) <= cfg.friction_tolerance
            for j, target in zip(cfg.friction_joints, self._friction_target, strict=True)
        )
        trigger = joints[self._trigger]
        if self.state is S.PASSIVE:
            self._enter(S.FEED, 'feeding a ball')

        state = self.state
        if state is S.FEED:
            target = self._feed(trigger, ball, now_ns, dt)
        elif state is S.BLOCK:
            target = self._reverse(trigger, now_ns)
        else:  # READY or PUSH
            target = self._fire(trigger, ball, now_ns, dt)
        if self.state is S.PASSIVE:  # gave up on a jam
            return
        targets = {
            j: JointTarget.with_velocity(v)
            for j, v in zip(cfg.friction_joints, self._friction_target, strict=True)
        }
        targets[self._trigger] = target
        self.send_joint_targets(targets)

    def _passive_reason(
        self, command: ShootCommand | None, joints: Mapping[str, JointState], now_ns: int
    ) -> str | None:
        if command is None:
            return 'no valid command on /shoot_cmd'
        if command.mode is ShootMode.PASSIVE:
            return 'commanded PASSIVE'
        if self._fault:
            return self._fault_reason
        missing = [
            j
            for j in self._joints
            if j not in joints
            or not joints[j].online
            or now_ns - joints[j].stamp_ns > self._joint_timeout_ns
        ]
        if missing:
            return f'no state from joint(s) {", ".join(missing)} (offline, stale or never seen)'
        return None

    def _go_passive(self, reason: str) -> None:
        self.zero_output()
        self._hold = None
        self._step_target = None
        self._detector.reset()
        self._friction_ready = False
        self._friction_target = [0.0] * len(self.config.friction_joints)
        self._speed = 0.0
        self.transition(S.PASSIVE, reason)

    def _enter(self, state: ShooterStage, reason: str) -> None:
        if state is not self.state:
            self._detector.reset()
        self.transition(state, reason)

    def _feed(self, trigger: JointState, ball: bool | None, now_ns: int, dt: float) -> JointTarget:
        cfg = self.config
        if ball:
            self._hold = trigger.position
            if self._jam_position is not None:
                # A recovery counts once the trigger got past the point where it jammed.
                past = (trigger.position - self._jam_position) * cfg.trigger_direction
                if past > cfg.step_tolerance:
                    self._attempts, self._jam_position = 0, None
            self._enter(S.READY, 'ball at the limit switch')
            return JointTarget.with_position(self._hold)
        # The trigger only ever turns forward with every friction wheel at speed, so a ball
        # never reaches stopped wheels.
        if not self._friction_ready:
            self._enter(S.FEED, _WAIT_FRICTION)
            self._detector.reset()
            return JointTarget.with_velocity(0.0)
        if ball is None:
            self._enter(S.FEED, self._wait_switch_text())
            self._detector.reset()
            return JointTarget.with_velocity(0.0)
        self._enter(S.FEED, 'feeding a ball')
        if self._jammed(trigger, dt):
            return self._start_block(trigger, now_ns)
        return JointTarget.with_velocity(cfg.feed_speed * cfg.trigger_direction)

    def _fire(self, trigger: JointState, ball: bool | None, now_ns: int, dt: float) -> JointTarget:
        cfg = self.config
        if self._hold is None:
            self._hold = trigger.position
        # Over a slot from where it was held (two during a step, which spans one): the
        # reference is lost, e.g. a bridge that restarted between two joint states with the
        # encoders back near zero. Driving the disc back to the old hold would turn it
        # without a command.
        off = abs(trigger.position - self._hold)
        if off > cfg.slot_angle * (2.0 if self._step_target is not None else 1.0):
            self._hold = self._step_target = None
            self._enter(S.FEED, f'trigger {off:.2f} rad from its hold: feeding again')
            self._detector.reset()
            return JointTarget.with_velocity(0.0)
        burst = self._burst
        if self._step_target is not None:  # a step in progress
            if self._jammed(trigger, dt):
                return self._start_block(trigger, now_ns)
            # The setpoint moves from the hold to the step's end at step_speed, with that
            # speed as feed-forward, so the trigger tracks it closely instead of creeping
            # up to a jump of a whole slot.
            moved = cfg.step_speed * (now_ns - self._step_start_ns) / _NS_PER_S
            if moved < cfg.slot_angle:
                setpoint = self._hold + moved * cfg.trigger_direction
                return JointTarget.with_position(setpoint, cfg.step_speed * cfg.trigger_direction)
            if abs(trigger.position - self._step_target) > cfg.step_tolerance:
                return JointTarget.with_position(self._step_target)
            self._hold, self._step_target = self._step_target, None
            self._shots_fired += 1
            self._attempts, self._jam_position = 0, None
            if burst is not None and burst.remaining is not None:
                burst.remaining -= 1
                if burst.remaining <= 0:
                    self._burst = burst = None
        if burst is None:
            reason = 'burst complete' if self.state is S.PUSH else 'ball at the limit switch'
            self._enter(S.READY, reason)
            return JointTarget.with_position(self._hold)
        hold = JointTarget.with_position(self._hold)
        heat = self._heat
        hz = burst.hz if heat is None else heat.rate_limit(burst.hz)
        if heat is not None and hz <= 0.0:
            self._enter(
                S.PUSH, f'barrel heat {heat.heat:.0f} of {heat.limit:.0f}: waiting for it to cool'
            )
            return hold
        if burst.last_step_ns is not None and now_ns - burst.last_step_ns < _NS_PER_S / hz:
            self._enter(S.PUSH, self._burst_text(burst))
            return hold
        if not self._friction_ready:
            self._enter(S.PUSH, _WAIT_FRICTION)
            return hold
        if ball is None:
            self._enter(S.PUSH, self._wait_switch_text())
            return hold
        if not ball:
            # The switch state comes through the gpio plugin a little later than the
            # trigger's position: believe "no ball" only once it has lasted a while.
            if self._no_ball_since_ns is None:
                self._no_ball_since_ns = now_ns
            if now_ns - self._no_ball_since_ns < cfg.switch_debounce * _NS_PER_S:
                self._enter(S.PUSH, self._burst_text(burst))
                return hold
            self._enter(S.FEED, 'no ball at the limit switch')
            return JointTarget.with_velocity(cfg.feed_speed * cfg.trigger_direction)
        self._no_ball_since_ns = None
        self._enter(S.PUSH, self._burst_text(burst))
        self._step_target = self._hold + cfg.slot_angle * cfg.trigger_direction
        burst.last_step_ns = self._step_start_ns = now_ns
        if heat is not None:
            heat.fired()  # counted as the step starts: the ball leaves within it
        self._detector.reset()
        return JointTarget.with_position(self._hold, cfg.step_speed * cfg.trigger_direction)

    def _wait_switch_text(self) -> str:
        return f'waiting for the limit switch {self.config.limit_switch!r} on /gpio_state'

    def _reverse(self, trigger: JointState, now_ns: int) -> JointTarget:
        cfg = self.config
        if abs(trigger.position - self._reverse_target) <= cfg.step_tolerance:
            self._enter(S.FEED, f'reversed {cfg.reverse_angle:g} rad after a jam; feeding')
        elif now_ns - self._block_start_ns >= cfg.block_timeout * _NS_PER_S:
            self._enter(
                S.FEED, f'reverse not done within {cfg.block_timeout:g} s after a jam; feeding'
            )
        else:
            return JointTarget.with_position(self._reverse_target)
        return JointTarget.with_velocity(cfg.feed_speed * cfg.trigger_direction)

    def _jammed(self, trigger: JointState, dt: float) -> bool:
        if dt <= 0.0:
            return self._detector.jammed
        return self._detector.update(trigger.effort, trigger.velocity, dt)

    def _start_block(self, trigger: JointState, now_ns: int) -> JointTarget:
        """A jam: reverse (BLOCK), or give up (PASSIVE + fault) after too many in a row."""
        cfg = self.config
        self._jam_count += 1
        self._attempts += 1
        self._step_target = None
        what = (
            f'jam {self._jam_count}: trigger effort {trigger.effort:.2f} N*m at '
            f'{trigger.velocity:.2f} rad/s for {self._detector.stalled_s:.2f} s'
        )
        if self._attempts > cfg.jam_retries:
            self._fault = True
            self._fault_reason = (
                f'fault: {what}; gave up after {cfg.jam_retries} recoveries; '
                'send a new burst_id or change mode'
            )
            self.logger.error(self._fault_reason)
            self._go_passive(self._fault_reason)
            return JointTarget.off()
        self._jam_position = trigger.position
        self._reverse_target = trigger.position - cfg.reverse_angle * cfg.trigger_direction
        self._block_start_ns = now_ns
        self._hold = None
        self._enter(S.BLOCK, f'{what}; reversing {cfg.reverse_angle:g} rad')
        return JointTarget.with_position(self._reverse_target)

    @staticmethod
    def _burst_text(burst: _Burst) -> str:
        if burst.remaining is None:
            return f'firing continuously at {burst.hz:g} shots/s'
        return f'firing a burst at {burst.hz:g} shots/s'

    # -- state topic --------------------------------------------------------------------------

    def _publish_state(self, now: Time, *, force: bool = False) -> None:
        now_ns = now.nanoseconds
        remaining = 0
        if self._burst is not None and self._burst.remaining is not None:
            remaining = self._burst.remaining
        key = (
            self.state,
            self.reason,
            self._friction_ready,
            self._shots_fired,
            remaining,
            self._jam_count,
            self._fault,
        )
        if not force and key == self._last_published and now_ns < self._next_publish_ns:
            return
        if not self.heard(self.state_pub):
            return
        self._last_published = key
        self._next_publish_ns = now_ns + self._state_period_ns
        joints = self.joint_states.snapshot(self.config.friction_joints)
        friction_speed = tuple(
            float(joints[j].velocity) if j in joints else 0.0 for j in self.config.friction_joints
        )
        report = _StateReport(
            now_ns, int(self.state.value), self.reason, float(self._speed),
            tuple(float(v) for v in self._friction_target), friction_speed,
            bool(self._friction_ready), self._shots_fired, remaining, self._jam_count,
            self._fault,
        )
        self.publish_built(self.state_pub, _shooter_state_message, report)  # by the edge


class _StateReport(NamedTuple):
    """What one /shooter_state says, kept by the loop for the edge's thread."""

    stamp_ns: int
    state: int
    reason: str
    bullet_speed: float
    friction_target: tuple[float, ...]
    friction_speed: tuple[float, ...]
    friction_ready: bool
    shots_fired: int
    burst_remaining: int
    jam_count: int
    fault: bool


def _shooter_state_message(report: _StateReport) -> ShooterState:
    """/shooter_state of one report (a new message each call)."""
    msg = ShooterState()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(report.stamp_ns, _NS_PER_S)
    msg.state = report.state
    msg.reason = report.reason
    msg.bullet_speed = report.bullet_speed
    msg.friction_target = list(report.friction_target)
    msg.friction_speed = list(report.friction_speed)
    msg.friction_ready = report.friction_ready
    msg.shots_fired = report.shots_fired
    msg.burst_remaining = report.burst_remaining
    msg.jam_count = report.jam_count
    msg.fault = report.fault
    return msg
