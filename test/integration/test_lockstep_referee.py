"""The standard robot against the simulated referee, in lockstep: heat, power, a lost link.

rm_sim's referee (rm_base.sim.referee) counts every projectile the simulated launcher fires
and measures the wheels' electrical power; it judges them by the 2026 rules (the launcher
locks over the heat limit, an empty buffer cuts the chassis for 5 s) and reports limits,
heat and buffer energy at 10 Hz, which the harness hands to the shooter and the chassis as
the Referee plugin would. Each check also runs without the robot's limit, to show the
simulated referee would have punished it.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import pytest
from geometry_msgs.msg import Twist
from support.lockstep import LockstepRobot

from rm_msgs.msg import ChassisCmd, GimbalCmd, ShootCmd

pytestmark = [pytest.mark.ros]

COMMAND_HZ = 50.0
HEAT_LIMIT = 100.0  # standard_sim.yaml sim.referee
COOLING = 10.0  # [1/s]
POWER_LIMIT = 60.0  # [W]
BUFFER_RESERVE = 20.0  # [J] standard.yaml chassis.power.buffer_reserve
# Full stick with snappy ramps (30 m/s^2): the power limit, not the ramp, bounds the drive.
SNAPPY = {
    f'chassis.ramp.linear.{kind}_acceleration': 30.0 for kind in ('launch', 'normal', 'brake')
}
NO_POWER_LIMIT = {'chassis.power.from_referee': False, 'chassis.power.default_limit': 400.0}


def robot(**overrides: object) -> LockstepRobot:
    r = LockstepRobot(overrides={'rm_robot': overrides})
    r.publish('/gimbal_cmd', GimbalCmd(mode=GimbalCmd.RATE), rate_hz=COMMAND_HZ)
    return r


def standing_by(r: LockstepRobot) -> None:
    r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.PASSIVE), rate_hz=COMMAND_HZ)
    r.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.READY, speed=15.0), rate_hz=COMMAND_HZ)
    r.run(1.5)


def burst(r: LockstepRobot, shots: int, seconds: float) -> tuple[list[float], float]:
    """Command shots at 20 Hz; return when each left the muzzle [s] and the referee's peak heat."""
    referee, launcher = r.world.referee, r.world.body.launcher
    r.publish(
        '/shoot_cmd',
        ShootCmd(mode=ShootCmd.PUSH, speed=15.0, hz=20.0, num=shots, burst_id=1),
        rate_hz=COMMAND_HZ,
    )
    times: list[float] = []
    peak = 0.0
    fired = launcher.shots
    for _ in range(round(seconds * 1000)):
        r.step()
        peak = max(peak, referee.rules.heat)
        if launcher.shots > fired:
            times += [r.t] * (launcher.shots - fired)
            fired = launcher.shots
    return times, peak


def full_stick(r: LockstepRobot, seconds: float) -> tuple[float, list[float]]:
    """Full stick forward and back each second; the lowest buffer [J] and each step's power."""
    referee = r.world.referee

    def stick() -> Twist:
        msg = Twist()
        msg.linear.x = 3.5 if int(r.t) % 2 == 0 else -3.5
        return msg

    r.publish('/shoot_cmd', ShootCmd(mode=ShootCmd.PASSIVE), rate_hz=COMMAND_HZ)
    r.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=COMMAND_HZ)
    r.publish('/vel_cmd', stick, rate_hz=COMMAND_HZ)
    lowest, powers = referee.rules.buffer_j, []
    for tick in range(round(seconds * 1000)):
        r.step()
        lowest = min(lowest, referee.rules.buffer_j)
        if tick % 100 == 99:
            powers.append(referee.rules.power_w)
    return lowest, powers


def gaps(times: list[float]) -> list[float]:
    return [b - a for a, b in itertools.pairwise(times)]


def run(overrides: dict[str, object], scenario: Callable[[LockstepRobot], object]) -> object:
    with robot(**overrides) as r:
        return scenario(r), r.world.referee.rules


def test_twenty_shots_at_20hz_stay_under_the_heat_limit_and_fire_as_fast_as_cooling_allows():
    def scenario(r: LockstepRobot) -> tuple[list[float], float]:
        standing_by(r)
        return burst(r, 20, 14.0)

    (times, peak), rules = run({}, scenario)
    assert len(times) == 20
    assert peak <= HEAT_LIMIT
    assert (rules.launcher_locks, rules.hp) == (0, 200)
    # the headroom at the shooter's top rate (10/s), then one shot per 10 heat cooled
    fast, steady = gaps(times)[:8], gaps(times)[10:]
    assert max(fast) < 0.15
    assert steady and all(abs(g - 10.0 / COOLING) < 0.05 for g in steady)


def test_without_the_heat_limit_the_referee_locks_the_launcher():
    def scenario(r: LockstepRobot) -> tuple[list[float], float]:
        standing_by(r)
        return burst(r, 20, 3.0)

    (_times, peak), rules = run({'shooter.heat.calibre': 0}, scenario)
    assert peak > HEAT_LIMIT
    assert rules.launcher_locks >= 1


def test_full_stick_under_60w_keeps_the_buffer_above_the_reserve_and_the_chassis_on():
    (lowest, powers), rules = run(SNAPPY, lambda r: full_stick(r, 10.0))
    assert rules.chassis_cuts == 0
    assert lowest >= BUFFER_RESERVE
    assert max(powers) > 1.3 * POWER_LIMIT  # the buffer above the reserve was spent
    assert abs(sum(powers[-40:]) / 40 - POWER_LIMIT) < 3.0  # then the limit, on average


def test_without_the_power_limit_the_referee_cuts_the_chassis():
    (lowest, _powers), rules = run({**SNAPPY, **NO_POWER_LIMIT}, lambda r: full_stick(r, 4.0))
    assert lowest == 0.0
    assert rules.chassis_cuts >= 1


def test_a_referee_link_lost_mid_run_falls_back_to_the_config_limits():
    def scenario(r: LockstepRobot) -> tuple[float, list[float], float]:
        standing_by(r)
        r.world.referee.unplug()
        r.run(1.5)  # past the shooter's and the chassis' referee_timeout (1 s)
        _times, peak = burst(r, 20, 3.0)
        lowest, powers = full_stick(r, 4.0)
        return peak, powers, lowest

    (peak, powers, lowest), rules = run(SNAPPY, scenario)
    # standard.yaml: heat.fallback_limit 50 (margin 10) and power.default_limit 60 W
    assert 30.0 <= peak <= 50.0
    assert max(powers) < POWER_LIMIT + 10.0  # the model's error, no buffer spent
    assert lowest > 50.0
    assert (rules.chassis_cuts, rules.launcher_locks) == (0, 0)
