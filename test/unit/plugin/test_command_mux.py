"""Command arbitration (rm_base.plugin.command_mux): priorities, timeouts, yielding."""

import pytest
from rm_base.plugin.command_mux import DEFAULT_SOURCES, CommandMux, CommandSource

MS = 1_000_000
TOPIC = '/chassis_cmd'
MANUAL = CommandSource('manual', '/manual', 100, 0.2)
EXTERNAL = CommandSource('external', '', 10, 0.5)


def mux_of(*sources, switches=None):
    mux = CommandMux(sources or (MANUAL, EXTERNAL),
                     on_switch=(lambda *a: switches.append(a)) if switches is not None else None)
    mux.add_topic(TOPIC)
    return mux


def test_each_source_subscribes_its_own_topic_highest_priority_first():
    mux = CommandMux((EXTERNAL, MANUAL))
    assert [(s.name, t) for s, t in mux.add_topic(TOPIC)] == [
        ('manual', '/manual/chassis_cmd'), ('external', '/chassis_cmd')]


def test_a_lone_source_is_in_charge():
    mux = mux_of()
    assert mux.offer(TOPIC, EXTERNAL, 0)
    assert mux.in_charge(TOPIC, 0) is EXTERNAL


def test_a_higher_live_source_wins_and_the_lower_one_yields_counted():
    switches = []
    mux = mux_of(switches=switches)
    assert mux.offer(TOPIC, EXTERNAL, 0)
    assert mux.offer(TOPIC, MANUAL, 10 * MS)
    assert not mux.offer(TOPIC, EXTERNAL, 20 * MS)
    report = mux.report(20 * MS)[TOPIC]
    assert report['in_charge'] == 'manual'
    assert report['yielded'] == {'manual': 0, 'external': 1}
    assert switches[-1] == (TOPIC, 'external', 'manual', 'priority 100 over 10')


def test_a_silent_source_yields_after_its_timeout_without_anyone_publishing():
    switches = []
    mux = mux_of(switches=switches)
    mux.offer(TOPIC, MANUAL, 0)
    assert not mux.offer(TOPIC, EXTERNAL, 200 * MS)  # manual's 0.2 s: still its
    assert mux.offer(TOPIC, EXTERNAL, 201 * MS)
    assert switches[-1] == (TOPIC, 'manual', 'external', 'manual silent for 0.201 s')
    assert mux.in_charge(TOPIC, 800 * MS) is None  # everyone silent


def test_topics_are_arbitrated_apart():
    mux = mux_of()
    mux.add_topic('/gimbal_cmd')
    mux.offer('/gimbal_cmd', MANUAL, 0)
    assert mux.offer(TOPIC, EXTERNAL, 0)  # the manual source holds the gimbal only


@pytest.mark.parametrize(('sources', 'match'), [
    ((MANUAL, CommandSource('manual', '/x', 5, 1.0)), 'name'),
    ((MANUAL, CommandSource('x', '/manual', 5, 1.0)), 'namespace'),
    ((MANUAL, CommandSource('x', '/x', 100, 1.0)), 'priority'),
    ((), 'at least one'),
])
def test_clashing_sources_are_refused(sources, match):
    with pytest.raises(ValueError, match=match):
        CommandMux(sources)


@pytest.mark.parametrize(('kwargs', 'match'), [
    ({'name': '1x'}, 'name'),
    ({'namespace': 'manual'}, 'absolute'),
    ({'namespace': '/manual/'}, 'absolute'),
    ({'timeout': 0.0}, 'timeout'),
    ({'timeout': float('nan')}, 'timeout'),
])
def test_a_bad_source_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CommandSource(**{'name': 'a', 'namespace': '/a', 'priority': 1, 'timeout': 1.0, **kwargs})


def test_the_default_puts_the_operator_above_everyone():
    assert [s.name for s in CommandMux(DEFAULT_SOURCES).sources] == ['manual', 'external']


def test_the_diagnostics_status_names_who_is_in_charge_and_the_counts():
    from rm_base.plugin.command_mux_status import command_sources_status

    mux = mux_of()
    mux.offer(TOPIC, EXTERNAL, 0)
    mux.offer(TOPIC, MANUAL, MS)
    mux.offer(TOPIC, EXTERNAL, 2 * MS)
    status = command_sources_status('rm_robot', mux, 3 * MS)
    values = {kv.key: kv.value for kv in status.values}
    assert status.name == 'rm_robot: command sources'
    assert status.message == 'in charge: /chassis_cmd manual'
    assert values['/chassis_cmd in charge'] == 'manual'
    assert values['/chassis_cmd external yielded'] == '1'
    assert values['/chassis_cmd external taken'] == '1'
    assert values['switches'] == '2'


def test_a_mux_knows_the_topics_it_arbitrates():
    mux = CommandMux((MANUAL, EXTERNAL))
    assert mux.topics == ()
    mux.add_topic('/shoot_cmd')
    mux.add_topic(TOPIC)
    assert mux.topics == (TOPIC, '/shoot_cmd')
