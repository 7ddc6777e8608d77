"""Replay of test/data/burst_jam: READY, a five-shot burst at 5 Hz with one jam, PASSIVE.

The robot runs the gpio (simulated ball switch) and shooter plugins of standard.yaml on
rm_sim. The scenario's fault schedule makes the trigger's first push from 0.5 s into the
burst on jam: the trigger locks, and frees when it pushes back (the shooter's BLOCK
reverse), as a wedged ball does (replay.scenarios.Jam). Measured (lockstep, the same on
every run): 5 shots, BLOCK once, the fifth shot 1.27 s after PUSH.
"""

from __future__ import annotations

import math

import pytest

from replay.scenarios import BURST_END_S, BURST_SHOTS, BURST_START_S, JAM_AT_S
from rm_msgs.msg import ShooterState

pytestmark = [pytest.mark.ros, pytest.mark.slow]

SLOT = 2.0 * math.pi / 8  # [rad] one shot: the trigger's 8 pockets


def entries(states, state):
    """How many times the sequence of states enters state."""
    return sum(1 for a, b in zip([None, *states], states, strict=False) if b == state and a != b)


def test_when_the_trigger_jams_mid_burst_expect_five_shots_and_one_block(replayed):
    result = replayed('burst_jam')
    info = f'{result.summary()} -> {result.output}'
    samples = result.samples('/shooter_state')
    states = [s.msg.state for s in samples]
    shots = [s.msg.shots_fired for s in samples]
    fifth = next((s for s in samples if s.msg.shots_fired >= BURST_SHOTS), None)
    print(
        f'burst: {max(shots)} shots, BLOCK entered {entries(states, ShooterState.BLOCK)}x, '
        f'jam_count {max(s.msg.jam_count for s in samples)}, 5th shot at '
        f'{fifth.t if fifth else None} s; faults {[(f.t, f.action) for f in result.faults]}'
    )
    # Exactly five shots, never more, and the last one while PUSH was still commanded.
    assert max(shots) == BURST_SHOTS, info
    assert fifth is not None and fifth.t < BURST_END_S, info
    # One jam: BLOCK entered once, counted once, no fault.
    assert entries(states, ShooterState.BLOCK) == 1, info
    assert max(s.msg.jam_count for s in samples) == 1, info
    assert not any(s.msg.fault for s in samples), info
    # The jam was armed, wedged at the next push and freed by the reverse while BLOCK.
    assert [f.action for f in result.faults] == ['armed', 'wedged', 'clear'], info
    block = next(s for s in samples if s.msg.state == ShooterState.BLOCK)
    assert JAM_AT_S <= result.faults[1].t <= block.t, info
    assert result.faults[2].t >= block.t - 0.05, info  # freed by BLOCK's reverse
    # After BLOCK the trigger fed again (FEED) and the burst went on.
    assert ShooterState.FEED in states[states.index(ShooterState.BLOCK) :], info


def test_when_the_burst_is_done_expect_ready_then_passive_as_commanded(replayed):
    result = replayed('burst_jam')
    info = f'{result.summary()} -> {result.output}'
    samples = result.samples('/shooter_state')
    fifth = next(s for s in samples if s.msg.shots_fired >= BURST_SHOTS)
    # PUSH held with the same burst_id after the burst: READY (no second burst).
    held = [s.msg for s in samples if fifth.t < s.t < BURST_END_S]
    assert held and held[-1].state == ShooterState.READY, info
    assert held[-1].burst_remaining == 0, info
    # Then PASSIVE as the bag commands it, and PASSIVE after the bag ends.
    final = result.last('/shooter_state')
    assert final.state == ShooterState.PASSIVE and not final.fault, info
    passive = [s.msg for s in samples if BURST_END_S + 0.1 < s.t < BURST_END_S + 0.4]
    assert passive and all(m.state == ShooterState.PASSIVE for m in passive), info
    assert 'commanded' in passive[-1].reason, info


def test_when_the_burst_is_done_expect_the_trigger_five_slots_on(replayed):
    result = replayed('burst_jam')
    info = f'{result.summary()} -> {result.output}'

    def trigger_at(t):
        msg = min(result.samples('/actuator_states'), key=lambda s: abs(s.t - t)).msg
        return msg.position[list(msg.name).index('trigger')]

    # READY with a ball at the switch before the burst and after it: the same phase of a
    # slot (the switch window), five slots on. The jam's reverse (0.4 rad) is undone by
    # the feed after it. Within half a slot: one shot more or less is a whole slot.
    advanced = trigger_at(BURST_END_S - 0.05) - trigger_at(BURST_START_S - 0.05)
    print(f'trigger advanced {advanced:.3f} rad = {advanced / SLOT:.2f} slots')
    assert advanced == pytest.approx(BURST_SHOTS * SLOT, abs=SLOT / 2), info
