"""RefereeHeatInput: the referee's reports reach the barrel model in the shooter's tick."""

import math

from rm_plugins.shooter.barrel_heat import BarrelHeat, BarrelHeatParams
from rm_plugins.shooter.heat import RefereeHeatInput

from rm_msgs.msg import RefereePowerHeat, RefereeRobotStatus, RefereeShot

S = 1_000_000_000  # ns


def model():
    return BarrelHeat(BarrelHeatParams(10.0, 10.0, fallback_limit=50.0, fallback_cooling_per_s=5.0))


def status(limit=240.0, cooling=40.0):
    return RefereeRobotStatus(barrel_heat_limit=limit, barrel_cooling=cooling)


def test_fresh_limits_apply_and_stale_ones_fall_back():
    heat, referee = model(), RefereeHeatInput(17, timeout_s=1.0)
    assert referee.apply(heat, 0) is False and heat.limit == 50.0  # nothing heard yet
    referee.on_robot_status(status(), 1 * S)
    assert referee.apply(heat, 1 * S) is True
    assert (heat.limit, heat.cooling_per_s) == (240.0, 40.0)
    assert referee.apply(heat, 3 * S) is False  # 2 s old
    assert (heat.limit, heat.cooling_per_s) == (50.0, 5.0)


def test_heat_and_shots_of_this_calibre_only():
    heat, referee = model(), RefereeHeatInput(42, timeout_s=1.0)
    referee.on_power_heat(RefereePowerHeat(heat_17mm=70.0, heat_42mm=100.0), 0)
    referee.on_shot(RefereeShot(bullet_type=RefereeShot.BULLET_17MM), 0)  # the other barrel
    referee.on_shot(RefereeShot(bullet_type=RefereeShot.BULLET_42MM), 0)
    referee.apply(heat, 0)
    # 100 from the report, +10 for the 42 mm shot nobody fired here (per-shot 10 in model())
    assert heat.heat == 110.0
    referee.apply(heat, 0)  # each report counts once
    assert heat.heat == 110.0


def test_a_heat_the_season_does_not_report_is_ignored():
    heat, referee = model(), RefereeHeatInput(17, timeout_s=1.0)
    heat.fired()
    referee.on_power_heat(RefereePowerHeat(heat_17mm=math.nan), 0)
    referee.apply(heat, 0)
    assert heat.heat == 10.0
