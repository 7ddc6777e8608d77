"""The soak's RefereeWatch: when the referee had joints unpowered, and the revival."""

import math
from types import SimpleNamespace

import pytest
from rm_base.sim import SimWorld

from reliability.referee_watch import RefereeWatch

OUTPUTS = {'chassis': ('wheel',), 'gimbal': ('yaw',), 'shooter': ('trigger',)}


@pytest.fixture
def world(tmp_path, monkeypatch):
    monkeypatch.setenv('RM_SIM_TEST_DIR', str(tmp_path))
    config = {
        'timing': 'stepped',
        'referee': {'path': '${RM_SIM_TEST_DIR}/referee', 'max_hp': 10},
    }
    with SimWorld.from_config(config) as w:
        yield w


def test_a_destroyed_robot_is_revived_and_every_joint_was_off_meanwhile(world):
    watch = RefereeWatch(world, OUTPUTS)
    rules = world.referee.rules
    watch.sample(100.0)
    assert not any(watch.off.values())
    for _ in range(60):  # far over twice the heat limit: all the HP at the next step
        rules.shot(0, 15.0)
    world.advance(0.1)
    assert rules.destroyed
    watch.sample(101.0)
    assert not rules.destroyed and rules.revivals == 1 and rules.outputs.shooter
    assert watch.off == {j: [[101.0, 101.0]] for j in ('wheel', 'yaw', 'trigger')}
    assert 'destroyed' in watch.events[0] and watch.summary()['revivals'] == 1
    assert watch.was_off(('yaw',), 100.5, 101.5)
    assert not watch.was_off(('yaw',), 101.5, 102.0)
    assert watch.was_off(('yaw',), 101.5, 102.0, settle_s=1.0)


def test_a_launcher_lock_is_an_open_window_on_the_shooter_until_the_heat_is_gone(world):
    watch = RefereeWatch(world, OUTPUTS)
    rules = world.referee.rules
    for _ in range(rules.settings.heat_limit // 10 + 1):  # just over the limit
        rules.shot(0, 15.0)
    watch.sample(10.0)
    assert not rules.outputs.shooter and rules.revivals == 0  # a lock, not for the match
    assert watch.off['trigger'] == [[10.0, math.inf]] and watch.off['wheel'] == []
    rules.revive()  # stands for the heat cooling off
    watch.sample(12.0)
    assert watch.off['trigger'] == [[10.0, 12.0]]
    watch.stop()
    assert watch.summary()['output_off_s'] == {'trigger': 2.0}


def test_a_miss_while_the_joint_was_unpowered_is_set_aside_as_not_judged(world):
    watch = RefereeWatch(world, OUTPUTS)
    watch.off['trigger'] = [[10.0, 12.0]]

    def record(target, start, end, detected=False):
        return SimpleNamespace(target=target, start=start, end=end, detected=detected, note='')

    during = record('trigger', 11.0, 11.5)
    settling = record('can1', 12.5, 13.0)  # a bus: its joints
    later = record('trigger', 14.0, 15.0)
    elsewhere = record('wheel', 11.0, 11.5)
    detected = record('trigger', 11.0, 11.5, detected=True)
    records = [during, settling, later, elsewhere, detected]
    watch.set_aside(records, lambda t: ('trigger',) if t in ('trigger', 'can1') else (t,), 1.0)
    assert [r.detected for r in records] == [None, None, False, False, True]
    assert 'referee' in during.note and later.note == ''


def test_a_world_without_referee_is_refused():
    with SimWorld(timing='stepped') as w, pytest.raises(ValueError, match='no referee'):
        RefereeWatch(w, OUTPUTS)
