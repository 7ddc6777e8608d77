"""The simulated referee's rules (docs/PROTOCOLS.md §6.6), one rule per test."""

import pytest
from rm_base.hardware.protocols.referee import ProtocolVersion as V
from rm_base.sim import SimConfigError
from rm_base.sim.referee_rules import STEP_NS, RefereeRules, RefereeSettings

LIMIT = 100


def rules(version=V.V2026, **kw):
    return RefereeRules(
        RefereeSettings(**{'version': version, 'heat_limit': LIMIT, 'cooling_per_s': 20, **kw})
    )


def steps(r, n, power=0.0, start=0):
    hurts = []
    for i in range(n):
        hurts += r.step((start + i + 1) * STEP_NS, power)
    return hurts


@pytest.mark.parametrize(('calibre', 'per_shot'), [(17, 10), (42, 100)])
def test_a_shot_heats_the_barrel_and_each_step_cools_a_tenth_of_the_cooling(calibre, per_shot):
    r = rules(calibre=calibre, heat_limit=1000) if calibre == 42 else rules()
    shot = r.shot(0, 15.0)
    assert (shot.bullet_type, shot.speed_mps) == ((1 if calibre == 17 else 2), 15.0)
    assert r.heat == per_shot
    steps(r, 1)
    assert r.heat == per_shot - 2.0  # cooling 20/s in a 100 ms step
    steps(r, 100)
    assert r.heat == 0.0  # never below 0


def test_the_firing_rate_is_reported_from_the_time_between_shots():
    r = rules()
    assert r.shot(0, 15.0).frequency_hz == 0
    assert r.shot(100_000_000, 15.0).frequency_hz == 10


def test_2026_over_the_limit_locks_the_launcher_until_the_heat_is_back_to_0():
    r = rules()
    for _ in range(11):
        r.shot(0, 15.0)
    assert r.heat == 110 and not r.outputs.shooter and r.launcher_locks == 1
    steps(r, 50)  # 110 heat at 2 per step: 55 steps to 0
    assert 0.0 < r.heat and not r.outputs.shooter
    steps(r, 5, start=50)
    assert r.heat == 0.0 and r.outputs.shooter
    assert r.hp == r.settings.max_hp  # 2025 on: no HP for heat under 2 x limit


def test_2026_more_than_100_over_the_limit_locks_the_launcher_for_the_match():
    r = rules()
    for _ in range(21):
        r.shot(0, 15.0)
    steps(r, 200)
    assert r.heat == 0.0 and not r.outputs.shooter


def test_2024_over_the_limit_costs_hp_each_step_and_never_locks():
    r = rules(V.V2024, max_hp=200)
    for _ in range(15):
        r.shot(0, 15.0)  # 150 heat
    hurts = steps(r, 1)  # cooled to 148: (48 / 250 / 10) * 200 = 3.84 -> 4 HP
    assert r.hp == 196 and [h.cause for h in hurts] == [3]
    assert r.outputs.shooter


@pytest.mark.parametrize('version', [V.V2024, V.V2026])
def test_twice_the_limit_costs_hp_at_once_and_sets_the_heat_to_twice_the_limit(version):
    r = rules(version, max_hp=250)
    for _ in range(25):
        r.shot(0, 15.0)  # 250 heat
    steps(r, 1)  # cooled to 248: (248 - 200) / 250 * 250 = 48 HP
    assert r.heat == 2 * LIMIT
    assert r.hp == 250 - 48


def test_power_over_the_limit_drains_the_buffer_and_under_it_refills_to_the_cap():
    r = rules(chassis_power_limit_w=60.0)
    steps(r, 10, power=80.0)  # 20 W over for 1 s
    assert r.buffer_j == pytest.approx(40.0)
    steps(r, 10, power=40.0, start=10)
    assert r.buffer_j == pytest.approx(60.0)
    steps(r, 10, power=0.0, start=20)
    assert r.buffer_j == 60.0  # the cap


def test_2026_an_empty_buffer_cuts_the_chassis_for_five_seconds():
    r = rules(chassis_power_limit_w=60.0)
    steps(r, 6, power=160.0)  # 10 J a step
    assert r.buffer_j == 0.0 and not r.outputs.chassis and r.chassis_cuts == 1
    assert r.robot_status().chassis_power is False
    steps(r, 49, start=6)
    assert not r.outputs.chassis
    steps(r, 1, start=55)
    assert r.outputs.chassis and r.chassis_cuts == 1
    assert r.hp == r.settings.max_hp


@pytest.mark.parametrize(('power', 'percent'), [(65.0, 10), (70.0, 20), (90.0, 40)])
def test_2024_an_empty_buffer_costs_hp_by_how_far_over_the_limit(power, percent):
    r = rules(V.V2024, chassis_power_limit_w=60.0, max_hp=1000, buffer_max_j=0.0)
    hurts = steps(r, 1, power=power)
    assert r.hp == 1000 - percent  # max HP x N % x 0.1 a step
    assert [h.cause for h in hurts] == [4] and r.outputs.chassis


def test_no_hp_left_turns_every_output_off():
    r = rules(V.V2024, max_hp=10, buffer_max_j=0.0)
    steps(r, 10, power=500.0)
    assert r.hp == 0
    assert (r.outputs.gimbal, r.outputs.chassis, r.outputs.shooter) == (False, False, False)


def test_a_revival_restores_hp_heat_buffer_and_every_output():
    r = rules(V.V2024, max_hp=10, buffer_max_j=0.0)
    steps(r, 10, power=500.0)
    assert r.destroyed
    r.revive()
    assert not r.destroyed and r.hp == 10 and r.revivals == 1
    assert (r.outputs.gimbal, r.outputs.chassis, r.outputs.shooter) == (True, True, True)


def test_a_revival_ends_a_lock_for_the_match():
    r = rules()
    for _ in range(21):
        r.shot(0, 15.0)
    assert r.locked_for_match and not r.outputs.shooter
    r.revive()
    assert not r.locked_for_match and r.heat == 0.0 and r.outputs.shooter


def test_reports_follow_the_season():
    new, old = rules(), rules(V.V2024)
    for r in (new, old):
        r.shot(0, 15.0)
        steps(r, 1, power=48.0)
    assert new.power_heat().chassis_power_w is None
    assert new.power_heat().heat_17mm == 8
    assert old.power_heat().chassis_power_w == 48.0
    assert old.power_heat().chassis_current_a == pytest.approx(2.0)
    assert new.projectile_allowance().allowance_17mm == 499
    assert old.projectile_allowance().fortress_17mm is None


@pytest.mark.parametrize(
    'bad',
    [{'calibre': 20}, {'heat_limit': -1}, {'max_hp': 0}, {'chassis_power_limit_w': float('nan')},
     {'robot_id': True}],
)
def test_impossible_settings_are_refused(bad):
    with pytest.raises(SimConfigError):
        RefereeSettings(**bad)
