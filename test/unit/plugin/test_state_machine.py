"""StateMachine: one transition method, a table, a listener. No ROS."""

import enum

import pytest
from rm_base.plugin import StateMachine, Transition, TransitionError


class Shooter(enum.IntEnum):
    PASSIVE = 0
    FEED = 1
    READY = 2
    PUSH = 3
    BLOCK = 4


TABLE = {
    Shooter.PASSIVE: {Shooter.FEED},
    Shooter.FEED: {Shooter.READY, Shooter.BLOCK},
    Shooter.READY: {Shooter.PUSH},
    Shooter.PUSH: {Shooter.FEED, Shooter.BLOCK},
    Shooter.BLOCK: {Shooter.FEED},
}


def make(**kwargs):
    seen = []
    machine = StateMachine(
        Shooter, Shooter.PASSIVE, safe=Shooter.PASSIVE, listener=seen.append, **kwargs
    )
    return machine, seen


def test_starts_in_the_initial_state_with_its_reason():
    machine, seen = make()
    assert machine.snapshot() == (Shooter.PASSIVE, 'initial state')
    assert seen == []


def test_transition_changes_state_and_tells_the_listener_once():
    machine, seen = make()
    assert machine.transition(Shooter.FEED, 'fire requested')
    assert machine.state is Shooter.FEED
    assert machine.reason == 'fire requested'
    assert seen == [Transition(Shooter.PASSIVE, Shooter.FEED, 'fire requested')]


def test_when_called_again_with_same_state_and_reason_expect_nothing():
    machine, seen = make()
    machine.transition(Shooter.FEED, 'fire requested')
    assert not machine.transition(Shooter.FEED, 'fire requested')
    assert len(seen) == 1


def test_when_same_state_gets_a_new_reason_expect_the_reason_published():
    machine, seen = make()
    machine.transition(Shooter.PASSIVE, 'no command on /shoot_cmd yet')
    assert machine.reason == 'no command on /shoot_cmd yet'
    assert seen == [Transition(Shooter.PASSIVE, Shooter.PASSIVE, 'no command on /shoot_cmd yet')]


def test_when_table_forbids_a_transition_expect_transition_error_and_no_change():
    machine, seen = make(allowed=TABLE)
    with pytest.raises(TransitionError, match=r'PASSIVE -> PUSH is not allowed.*FEED'):
        machine.transition(Shooter.PUSH, 'fire')
    assert machine.state is Shooter.PASSIVE
    assert seen == []


def test_when_table_allows_the_path_expect_each_step_accepted():
    machine, _ = make(allowed=TABLE)
    for state in (Shooter.FEED, Shooter.READY, Shooter.PUSH, Shooter.BLOCK, Shooter.FEED):
        machine.transition(state, 'step')
    assert machine.state is Shooter.FEED


def test_the_safe_state_is_always_reachable():
    machine, _ = make(allowed=TABLE)
    machine.transition(Shooter.FEED, 'go')
    machine.transition(Shooter.READY, 'ball in place')
    # READY -> PASSIVE is not in the table, but PASSIVE is the safe state.
    assert machine.transition(Shooter.PASSIVE, 'command lost')
    assert not machine.can_transition(Shooter.READY)


def test_when_state_is_not_a_member_expect_type_error():
    machine, _ = make()

    class Other(enum.IntEnum):
        PASSIVE = 0

    with pytest.raises(TypeError, match='not a member of Shooter'):
        machine.transition(Other.PASSIVE, 'wrong enum')
