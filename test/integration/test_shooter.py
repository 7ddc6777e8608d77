"""rm_plugins/StandShooter end to end on the simulated robot, in lockstep.

Each test runs the standard robot (support.lockstep: the loop, the plugins and rm_sim
stepped together on a simulated clock) with the ``gpio`` plugin (simulated backend: the
ball switch closes while the trigger's phase is in its window) and the ``shooter``
plugin, streams /shoot_cmd at 50 Hz, and records /shooter_state, /gpio_state and the
joints every 5 ms. Tests step until a condition holds and check the physical outcome on
the sim's motors (trigger angle, friction wheel speeds); the numbers are the same on
every run.
"""

from __future__ import annotations

import math
from typing import Any

import numpy
import pytest
from rm_base.sim import Fault, FaultKind
from support.lockstep import LockstepRobot

from rm_msgs.msg import RefereeRobotStatus, ShootCmd, ShooterState

pytestmark = pytest.mark.ros

WAIT = 10.0  # longest wait for a condition [s]
SLOT = 2.0 * math.pi / 8  # the trigger's slot: 8 pockets -> 0.785 rad per shot

# A friction wheel + hub of ~100 g at r = 30 mm on the M3508 rotor (gear 1):
# 0.5 * 0.1 * 0.03^2 = 4.5e-5 kg*m^2 (the rotor adds its own 1.2e-5).
FRICTION_LOAD_INERTIA = 4.5e-5
# The bridge clamps velocity targets to the motor type's default (an M3508's ~50 rad/s
# behind its gearbox); a direct-drive rotor runs to ~1000 rad/s at 24 V.
FRICTION_MAX_VELOCITY = 1000.0  # [rad/s]
TRIGGER_LOAD_INERTIA = 2e-4  # [kg*m^2] the trigger disc with balls, at the output shaft
SAMPLE_NS = 5_000_000  # joints sampled every 5 ms, as the bridge publishes them


class ShooterRig:
    """SimRobot with gpio + shooter, a /shoot_cmd stream and recorders."""

    def __init__(self, **shooter: Any) -> None:
        bridge = {}
        for wheel in ('friction_l', 'friction_r'):
            bridge[f'joints.{wheel}.sim.load_inertia'] = FRICTION_LOAD_INERTIA
            bridge[f'joints.{wheel}.max_velocity'] = FRICTION_MAX_VELOCITY
        bridge['joints.trigger.sim.load_inertia'] = TRIGGER_LOAD_INERTIA
        self.robot = LockstepRobot(
            'standard',
            plugins=('gpio', 'shooter'),
            overrides={
                'can_bridge': bridge,
                'rm_robot': {f'shooter.{k}': v for k, v in shooter.items()},
            },
        )
        self.robot_params = self.robot.host_parameters
        self.host = self.robot.host
        self.world = self.robot.world
        self.robot.watch('/shooter_state', keep_history=True)
        self.robot.watch('/gpio_state')
        self.samples: list[tuple[float, dict[str, float], dict[str, float]]] = []
        self.robot.on_tick(self._sample_joints)
        self.command: ShootCmd | None = None

    def _sample_joints(self) -> None:
        if self.world.time_ns % SAMPLE_NS:
            return
        joints = {n: self.robot.joint(n) for n in ('friction_l', 'friction_r', 'trigger')}
        position = {n: j['position'] for n, j in joints.items()}
        velocity = {n: j['velocity'] for n, j in joints.items()}
        self.samples.append((self.now(), position, velocity))

    def now(self) -> float:
        """Sim time [s]."""
        return self.robot.t

    def wait_until(self, predicate: Any, timeout: float = WAIT) -> bool:
        """Step the robot until predicate() holds, for at most timeout [s] of sim time."""
        return self.robot.wait_until(predicate, timeout)

    # -- commands and states ------------------------------------------------------------------

    def send(
        self, mode: int, speed: float = 15.0, hz: float = 0.0, num: int = 0, burst_id: int = 0
    ):
        """Publish this ShootCmd at 50 Hz from now on."""
        self.resend(
            ShootCmd(mode=mode, speed=float(speed), hz=float(hz), num=num, burst_id=burst_id)
        )

    def resend(self, command: ShootCmd) -> None:
        """Publish command at 50 Hz from now on (stamped at each publish)."""
        self.command = command
        self.robot.publish('/shoot_cmd', command, rate_hz=50.0)

    def stop_commands(self) -> None:
        self.robot.stop_publishing('/shoot_cmd')

    @property
    def switch(self) -> float | None:
        msg = self.robot.latest('/gpio_state')
        return None if msg is None else dict(zip(msg.name, msg.value, strict=True))['ball_switch']

    def state(self) -> ShooterState | None:
        return self.robot.latest('/shooter_state')

    def in_state(self, state: int) -> bool:
        latest = self.state()
        return latest is not None and latest.state == state

    def states_since(self, index: int) -> list[ShooterState]:
        return self.robot.history('/shooter_state')[index:]

    def mark(self) -> int:
        return len(self.robot.history('/shooter_state'))

    # -- sim ground truth ---------------------------------------------------------------------

    def trigger_angle(self) -> float:
        """The trigger motor's output angle [rad] (joint direction +1)."""
        with self.world.lock:
            return self.world.motor('trigger').model.angle

    def trigger_speed(self) -> float:
        """The trigger motor's output speed [rad/s]."""
        with self.world.lock:
            return self.world.motor('trigger').model.velocity

    def wheel_speeds(self) -> tuple[float, float]:
        """|speed| of both friction wheel motors [rad/s] (friction_r turns the other way)."""
        with self.world.lock:
            return tuple(
                abs(self.world.motor(w).model.velocity) for w in ('friction_l', 'friction_r')
            )

    def lookup(self, speed: float) -> float:
        """Wheel speed for a bullet speed from the config's table (linear in between)."""
        params = self.robot_params
        return float(
            numpy.interp(speed, params['shooter.bullet_speeds'], params['shooter.wheel_speeds'])
        )

    def trigger_positions_since(self, t0: float) -> list[float]:
        """Trigger joint positions sampled since sim time t0 [s]."""
        return [p['trigger'] for t, p, _ in self.samples if t >= t0]

    def close(self) -> None:
        self.robot.close()


@pytest.fixture
def rig():
    made = []

    def make(**shooter):
        made.append(ShooterRig(**shooter))
        return made[-1]

    yield make
    for r in made:
        r.close()


def ready(r: ShooterRig, speed: float = 15.0) -> None:
    """Command READY and wait for it (wheels at speed, a ball at the switch)."""
    r.send(ShootCmd.READY, speed=speed)
    assert r.wait_until(lambda: r.in_state(ShooterState.READY), WAIT), r.state()
    settle(r)


def settle(r: ShooterRig) -> None:
    """Wait until the trigger has come to rest (after a feed or a step)."""
    assert r.wait_until(lambda: abs(r.trigger_speed()) < 0.01, WAIT), r.trigger_speed()


# -- tests ------------------------------------------------------------------------------------


def test_both_plugins_load_by_name_and_the_shooter_starts_passive(rig):
    r = rig()
    assert type(r.host.plugin('shooter')).__module__ == 'rm_plugins.shooter.plugin'
    assert type(r.host.plugin('gpio')).__module__ == 'rm_plugins.gpio.plugin'
    assert r.wait_until(lambda: r.state() is not None and r.switch is not None, WAIT)
    assert r.state().state == ShooterState.PASSIVE
    assert 'no command' in r.state().reason


def test_when_ready_expect_wheels_at_the_looked_up_speed_and_a_ball_fed(rig):
    r = rig()
    ready(r, speed=15.0)
    # 15 m/s -> 470 rad/s from the table; the sim's wheels within the 25 rad/s tolerance.
    expected = r.lookup(15.0)
    assert expected == 470.0
    assert r.wait_until(lambda: all(abs(w - expected) < 25.0 for w in r.wheel_speeds()), WAIT)
    print('wheel speeds', r.wheel_speeds(), 'expected', expected)
    # The ball: the switch reports it, and physically the trigger's phase is in the window.
    assert r.wait_until(lambda: r.switch == 1.0, WAIT)
    phase = r.trigger_angle() % SLOT
    low, high = 0.15, 0.55  # gpio.pins.ball_switch.sim_window
    print('trigger phase in READY', phase)
    assert low <= phase <= high
    assert r.state().friction_ready


def shots(r: ShooterRig) -> int:
    latest = r.state()
    return latest.shots_fired if latest is not None else 0


def test_when_push_5_at_5_hz_expect_5_slot_steps_and_5_shots_in_about_a_second(rig):
    r = rig()
    ready(r)
    angle0 = r.trigger_angle()
    r.send(ShootCmd.PUSH, speed=15.0, hz=5.0, num=5, burst_id=1)
    t0 = r.now()
    assert r.wait_until(lambda: shots(r) >= 5, WAIT), r.state()
    elapsed = r.now() - t0
    assert r.wait_until(lambda: r.in_state(ShooterState.READY), WAIT), r.state()
    settle(r)
    advanced = r.trigger_angle() - angle0
    print(f'5 shots in {elapsed:.3f} s, trigger advanced {advanced:.4f} rad')
    # Five slot steps: 5 * 2*pi/8 = 3.927 rad. Each step ends within step_tolerance
    # (0.05 rad) and the hold settles against Coulomb friction (~0.005 rad measured); 0.08
    # rad is a tenth of a slot, while a step too many or too few would be 0.785 rad.
    assert abs(advanced - 5 * SLOT) < 0.08
    assert shots(r) == 5 and r.state().burst_remaining == 0
    # Steps begin 1/hz = 0.2 s apart: at 0, 0.2, .., 0.8 s; each moves its slot at
    # step_speed 12 rad/s (0.785 / 12 = 65 ms) and settles within step_tolerance, so the
    # fifth shot counts ~0.9 s after the command, later where a step waits for its ball
    # at the switch. Accepted: 0.8 s (never faster than the rate) to 1.2 s.
    assert 0.8 <= elapsed <= 1.2


def test_when_the_same_push_command_repeats_expect_no_second_burst(rig):
    r = rig()
    ready(r)
    r.send(ShootCmd.PUSH, speed=15.0, hz=10.0, num=2, burst_id=7)
    assert r.wait_until(lambda: shots(r) >= 2 and r.in_state(ShooterState.READY), WAIT)
    settle(r)
    angle = r.trigger_angle()
    mark = r.mark()
    # The same command keeps coming at 50 Hz; over the next 25 states (0.5 s at 50 Hz) not
    # one more shot, and the trigger holds (it may still creep back onto its hold against
    # friction: up to 0.19 rad seen after an overshoot; another step would be 0.785 rad).
    assert r.wait_until(lambda: r.mark() >= mark + 25, WAIT)
    assert {s.shots_fired for s in r.states_since(mark)} == {2}
    assert abs(r.trigger_angle() - angle) < 0.3
    # A new burst_id fires again.
    r.send(ShootCmd.PUSH, speed=15.0, hz=10.0, num=1, burst_id=8)
    assert r.wait_until(lambda: shots(r) >= 3, WAIT)


def test_when_push_from_passive_expect_no_trigger_motion_before_the_wheels_are_at_speed(rig):
    r = rig()
    assert r.wait_until(lambda: r.state() is not None, WAIT)
    t0 = r.now()
    start = r.trigger_angle()
    r.send(ShootCmd.PUSH, speed=30.0, hz=5.0, num=2, burst_id=1)
    assert r.wait_until(lambda: shots(r) >= 2, WAIT), r.state()
    # The wheels' target at 30 m/s: 780 rad/s; find when both were first within 25 rad/s
    # (the joints as the plugin sees them) and check the trigger before that.
    target = r.lookup(30.0)
    samples = [(t, p, v) for t, p, v in r.samples if t >= t0]
    at_speed = next(
        t
        for t, _, v in samples
        if all(abs(v[w] - target) <= 25.0 for w in ('friction_l', 'friction_r'))
    )
    before = [p['trigger'] for t, p, _ in samples if t < at_speed]
    print(f'wheels at speed {at_speed - t0:.3f} s after PUSH; {len(before)} samples before')
    assert len(before) >= 5  # the spin-up from rest takes ~0.15 s: 0.29 N*m on 5.7e-5 kg*m^2
    assert max(abs(p - start) for p in before) < 0.01
    # Then the ball is fed and two slots fired: at least 2 * 0.785 rad on.
    assert r.trigger_angle() - start > 2 * SLOT


def test_when_the_trigger_jams_expect_block_reverse_feed_and_the_burst_completed(rig):
    r = rig()
    ready(r)
    r.send(ShootCmd.PUSH, speed=15.0, hz=5.0, num=5, burst_id=1)
    assert r.wait_until(lambda: shots(r) >= 1, WAIT)
    mark = r.mark()
    r.world.inject('trigger', Fault.jam())  # locked rotor: the next step stalls
    assert r.wait_until(
        lambda: any(s.state == ShooterState.BLOCK for s in r.states_since(mark)), WAIT
    ), r.state()
    jammed_at = r.trigger_angle()
    t_block = r.now()
    r.world.clear_faults('trigger', FaultKind.JAM)  # the ball comes free
    assert r.wait_until(lambda: shots(r) >= 5 and r.in_state(ShooterState.READY), WAIT), r.state()
    seen = [s.state for s in r.states_since(mark)]
    block = seen.index(ShooterState.BLOCK)
    assert ShooterState.FEED in seen[block:]  # BLOCK -> FEED -> READY/PUSH
    assert r.state().jam_count == 1 and not r.state().fault
    # The reverse happened in the sim: back by about reverse_angle = 0.4 rad.
    lowest = min(r.trigger_positions_since(t_block))
    print(f'jammed at {jammed_at:.3f} rad, reversed to {lowest:.3f} rad')
    assert jammed_at - lowest > 0.3


def test_when_the_trigger_stays_jammed_expect_passive_with_a_fault_until_a_new_burst(rig):
    r = rig()
    ready(r)
    r.world.inject('trigger', Fault.jam())
    r.send(ShootCmd.PUSH, speed=15.0, hz=5.0, num=3, burst_id=1)
    # jam_retries = 3 recoveries, the 4th jam in a row gives up.
    assert r.wait_until(lambda: r.state().fault, WAIT), r.state()
    state = r.state()
    print('fault:', state.reason)
    assert state.state == ShooterState.PASSIVE
    assert state.jam_count == 4 and state.shots_fired == 0
    assert 'fault' in state.reason
    # Repeating the command keeps the fault (25 states, 0.5 s).
    mark = r.mark()
    assert r.wait_until(lambda: r.mark() >= mark + 25, WAIT)
    assert all(s.fault and s.state == ShooterState.PASSIVE for s in r.states_since(mark))
    # A new burst clears it and, with the trigger free again, fires.
    r.world.clear_faults('trigger', FaultKind.JAM)
    r.send(ShootCmd.PUSH, speed=15.0, hz=5.0, num=3, burst_id=2)
    assert r.wait_until(lambda: shots(r) >= 3, WAIT), r.state()
    assert not r.state().fault


def test_when_the_command_stops_expect_passive_and_the_wheels_coasting(rig):
    r = rig()
    ready(r)
    r.stop_commands()
    # command_timeout 0.2 s: PASSIVE, joints off; the wheels coast down on their own friction.
    assert r.wait_until(lambda: r.in_state(ShooterState.PASSIVE), WAIT)
    assert 'no command' in r.state().reason
    speed = min(r.wheel_speeds())
    assert r.wait_until(lambda: max(r.wheel_speeds()) < 0.8 * speed, WAIT)


def test_when_the_command_returns_after_a_dropout_expect_the_burst_not_fired_again(rig):
    r = rig()
    ready(r)
    r.send(ShootCmd.PUSH, speed=15.0, hz=10.0, num=2, burst_id=3)
    assert r.wait_until(lambda: shots(r) >= 2, WAIT)
    command = r.command
    r.stop_commands()
    assert r.wait_until(lambda: r.in_state(ShooterState.PASSIVE), WAIT)
    r.resend(command)  # the same PUSH, burst 3, comes back
    assert r.wait_until(lambda: r.in_state(ShooterState.READY), WAIT), r.state()
    mark = r.mark()
    assert r.wait_until(lambda: r.mark() >= mark + 25, WAIT)
    assert {s.shots_fired for s in r.states_since(mark)} == {2}


def test_a_burst_cut_short_by_a_dropout_fires_only_its_shots_left_when_it_comes_back(rig):
    # README's hero burst: the commander's stream paused longer than command_timeout
    # (0.2 s) in the middle of a burst of 5; the same PUSH back finishes the 5, no more.
    r = rig()
    ready(r)
    r.send(ShootCmd.PUSH, speed=15.0, hz=5.0, num=5, burst_id=4)
    assert r.wait_until(lambda: shots(r) >= 1, WAIT)
    command = r.command
    r.stop_commands()
    assert r.wait_until(lambda: r.in_state(ShooterState.PASSIVE), WAIT)
    fired = shots(r)
    assert fired < 5
    r.resend(command)
    assert r.wait_until(lambda: shots(r) >= 5, WAIT), (fired, r.state())
    mark = r.mark()
    assert r.wait_until(lambda: r.mark() >= mark + 25, WAIT)
    assert {s.shots_fired for s in r.states_since(mark)} == {5}


@pytest.mark.parametrize(
    ('fields', 'reason'),
    [
        ({'mode': 7}, 'unknown mode 7'),
        ({'mode': ShootCmd.READY, 'speed': math.nan}, 'speed must be a finite number'),
        ({'mode': ShootCmd.PUSH, 'speed': 15.0, 'hz': math.inf}, 'hz must be a finite'),
        ({'mode': ShootCmd.PUSH, 'speed': 15.0, 'hz': 0.0}, 'hz > 0'),
    ],
)
def test_when_the_command_is_invalid_expect_it_rejected_and_nothing_moving(rig, fields, reason):
    r = rig()
    r.resend(ShootCmd(**fields))
    assert r.wait_until(
        lambda: r.state() is not None and reason in r.state().reason, WAIT
    ), r.state()
    assert r.state().state == ShooterState.PASSIVE
    mark = r.mark()
    assert r.wait_until(lambda: r.mark() >= mark + 10, WAIT)
    assert max(r.wheel_speeds()) < 1.0 and abs(r.trigger_angle()) < 0.01


def test_with_a_heat_limit_a_burst_stops_under_it_and_goes_on_as_fast_as_the_barrel_cools(rig):
    r = rig(**{'heat.calibre': 17})  # 10 heat a shot, one shot of margin (10)
    # the referee: limit 40, cooling 10 heat/s (a tenth every 100 ms), the barrel cold
    r.robot.publish(
        '/referee/robot_status',
        RefereeRobotStatus(barrel_heat_limit=40.0, barrel_cooling=10.0, chassis_power_limit=60.0),
        rate_hz=10.0,
    )
    ready(r)
    r.send(ShootCmd.PUSH, speed=15.0, hz=10.0, num=8, burst_id=1)
    t0 = r.now()
    # (40 - 10) / 10 = 3 shots at once (heat 30), then each as cooling frees one (1 s)
    assert r.wait_until(lambda: shots(r) >= 3, WAIT), r.state()
    assert r.wait_until(lambda: r.now() - t0 >= 0.8, WAIT)
    assert shots(r) == 3 and 'barrel heat' in r.state().reason
    # ...and then at what cooling sustains: 10 heat/s = one shot a second
    assert r.wait_until(lambda: r.now() - t0 >= 3.0, WAIT)
    assert 4 <= shots(r) <= 6, (shots(r), r.state().reason)
    assert r.state().state == ShooterState.PUSH


def test_with_the_referee_silent_the_heat_limit_falls_back_never_to_none(rig):
    # no /referee/* at all: the fallback limit 5 shots' heat (50), margin one shot -> 4
    r = rig(**{'heat.calibre': 17})
    ready(r)
    r.send(ShootCmd.PUSH, speed=15.0, hz=10.0, num=8, burst_id=1)
    t0 = r.now()
    assert r.wait_until(lambda: r.now() - t0 >= 1.0, WAIT)
    assert shots(r) == 4 and 'barrel heat' in r.state().reason
