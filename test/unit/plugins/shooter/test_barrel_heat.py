"""BarrelHeat: the referee's cooling steps, syncing, and never passing the limit."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rm_base.errors import ConfigError, InputRejectedError
from rm_plugins.shooter.barrel_heat import BarrelHeat, BarrelHeatParams

PARAMS = BarrelHeatParams(heat_per_shot=10.0, margin=20.0, fallback_limit=50.0,
                          fallback_cooling_per_s=10.0)


def heat_at(value, limit=240.0, cooling=40.0, params=PARAMS):
    heat = BarrelHeat(params)
    heat.set_limits(limit, cooling)
    heat.referee_heat(value)
    return heat


def test_cooling_comes_in_100_ms_steps_and_stops_at_zero():
    heat = heat_at(100.0)
    heat.step(0.05)
    assert heat.heat == 100.0  # no step yet
    heat.step(0.05)
    assert heat.heat == pytest.approx(96.0)  # 40/s: 4 per 100 ms
    for _ in range(9):
        heat.step(0.1)
    assert heat.heat == pytest.approx(60.0)
    heat.step(5.0)
    assert heat.heat == 0.0


def test_shots_count_at_once_and_the_margin_stays_free():
    heat = heat_at(180.0)
    # (240 - 20 - 180) / 10 = 4 shots left
    assert heat.shots_allowed() == 4
    for _ in range(4):
        heat.fired()
    assert heat.shots_allowed() == 0 and heat.heat == 220.0


def test_the_referee_heat_counts_with_our_shots_it_has_not_reported():
    heat = heat_at(0.0)
    heat.fired()
    heat.fired()
    heat.referee_heat(5.0)  # sampled before both shots
    assert heat.heat == 25.0
    heat.referee_shot()  # 0x0207 for the first
    heat.referee_heat(15.0)  # sampled after it, before the second
    assert heat.heat == 25.0
    heat.referee_shot()
    heat.referee_heat(20.0)
    assert heat.heat == 20.0


def test_a_shot_the_referee_never_reports_is_forgotten_after_the_timeout():
    heat = heat_at(0.0)
    heat.fired()
    heat.step(0.6)  # > confirm_timeout 0.5 s
    heat.referee_heat(0.0)
    assert heat.heat == 0.0


def test_a_shot_only_the_referee_saw_adds_its_heat():
    heat = heat_at(0.0)
    heat.referee_shot()
    assert heat.heat == 10.0


def test_a_silent_referee_means_the_fallback_limits_never_none():
    heat = heat_at(0.0)
    heat.use_fallback()
    assert (heat.limit, heat.cooling_per_s) == (50.0, 10.0)
    assert heat.shots_allowed() == 3  # (50 - 20) / 10


@pytest.mark.parametrize(
    ('referee_heat', 'requested', 'expected'),
    [
        (0.0, 20.0, 20.0),  # 22 shots of headroom: as asked
        (195.0, 20.0, 4.0),  # 2 shots left: what 40/s of cooling sustains (4 shots/s)
        (195.0, 2.0, 2.0),  # slower than that anyway
        (215.0, 20.0, 0.0),  # no whole shot left
    ],
)
def test_near_the_limit_the_rate_drops_to_what_cooling_sustains(referee_heat, requested, expected):
    smooth = BarrelHeatParams(10.0, 20.0, 50.0, 10.0, steady_headroom=3.0)
    assert heat_at(referee_heat, params=smooth).rate_limit(requested) == expected


def test_by_default_the_whole_headroom_fires_at_the_asked_rate():
    assert heat_at(195.0).rate_limit(20.0) == 20.0  # 2 shots left
    assert heat_at(215.0).rate_limit(20.0) == 0.0


def test_bad_values_are_refused():
    with pytest.raises(ConfigError, match='heat_per_shot'):
        BarrelHeatParams(heat_per_shot=0.0, margin=0.0, fallback_limit=1.0,
                         fallback_cooling_per_s=0.0)
    with pytest.raises(ConfigError, match='steady_headroom'):
        BarrelHeatParams(10.0, 0.0, 50.0, 10.0, steady_headroom=0.5)
    heat = BarrelHeat(PARAMS)
    with pytest.raises(InputRejectedError):
        heat.referee_heat(math.nan)
    with pytest.raises(InputRejectedError):
        heat.step(0.0)


@settings(max_examples=60, deadline=None)
@given(
    rate_hz=st.floats(1.0, 30.0),
    latency_s=st.sampled_from([0.0, 0.05, 0.13, 0.2, 0.3]),
    cooling=st.sampled_from([10.0, 40.0, 80.0]),
    referee_phase_ms=st.integers(0, 99),
)
def test_firing_only_when_allowed_never_passes_the_referees_limit(
    rate_hz, latency_s, cooling, referee_phase_ms
):
    """A 1 kHz lockstep of the shooter and a referee that reports late.

    The referee's true heat is what a barrel is judged by. Its reports (heat every 100 ms,
    a shot report after each projectile) arrive latency_s late; its cooling steps fall at
    its own phase. Our estimate may cool one step before the referee does, so a margin of
    one cooling step keeps the true heat under the limit.
    """
    limit, per_shot = 240.0, 10.0
    params = BarrelHeatParams(per_shot, margin=cooling * 0.1, fallback_limit=limit,
                              fallback_cooling_per_s=cooling)
    heat = BarrelHeat(params)
    true_heat = 0.0
    events: list[tuple[int, str, float]] = []  # (delivery ms, kind, value)
    next_shot_ms = 0.0
    for ms in range(4000):
        if (ms - referee_phase_ms) % 100 == 0:
            true_heat = max(0.0, true_heat - cooling * 0.1)
        if ms % 100 == 0:
            events.append((ms + round(latency_s * 1000), 'heat', true_heat))
        heat.step(0.001)
        for event in [e for e in events if e[0] <= ms]:
            events.remove(event)
            if event[1] == 'heat':
                heat.referee_heat(event[2])
            else:
                heat.referee_shot()
        if ms >= next_shot_ms and heat.shots_allowed() >= 1:
            heat.fired()
            true_heat += per_shot
            events.append((ms + round(latency_s * 1000), 'shot', 0.0))
            next_shot_ms = ms + 1000.0 / rate_hz
        assert true_heat <= limit, f'{true_heat} at {ms} ms'
