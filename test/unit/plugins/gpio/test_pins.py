"""Pin descriptions, the simulated ball switch model and GpioCmd checks."""

import math

import pytest
from rm_plugins.gpio import (
    GpioCommandError,
    GpioConfigError,
    JointPhaseSwitch,
    PinKind,
    PinSpec,
    check_command,
    value_problem,
)

PINS = {
    'switch': PinSpec('switch', PinKind.INPUT),
    'laser': PinSpec('laser', PinKind.OUTPUT),
    'servo': PinSpec('servo', PinKind.PWM, initial=0.075),
}

# 8 pockets: a slot is 2*pi/8 = pi/4 = 0.7854 rad; the switch closes in [0.2, 0.5] rad.
SWITCH = JointPhaseSwitch('trigger', 8, (0.2, 0.5))
SLOT = math.pi / 4


@pytest.mark.parametrize(
    ('position', 'closed'),
    [
        (0.0, False),  # phase 0: between two pockets
        (0.3, True),  # phase 0.3 in [0.2, 0.5]
        (0.3 + SLOT, True),  # one slot on: the next ball, same phase
        (0.3 + 5 * SLOT, True),  # five slots on
        (0.6, False),  # phase 0.6 > 0.5: the pocket has passed the switch
        (0.3 - SLOT, True),  # one slot back: phase -0.4854 mod 0.7854 = 0.3
        (-0.1, False),  # phase -0.1 + 0.7854 = 0.6854 > 0.5
        (-0.4, True),  # phase -0.4 + 0.7854 = 0.3854 in the window
    ],
)
def test_when_the_joint_turns_expect_the_switch_closed_once_per_slot(position, closed):
    assert SWITCH.closed(position) is closed


def test_when_the_position_is_negative_expect_a_phase_in_the_slot():
    # -3 slots - 0.1 rad -> phase SLOT - 0.1
    assert SWITCH.phase(-3 * SLOT - 0.1) == pytest.approx(SLOT - 0.1)
    assert 0.0 <= SWITCH.phase(-1e-18) < SLOT


@pytest.mark.parametrize(
    ('slots', 'window', 'match'),
    [
        (0, (0.1, 0.2), 'sim_slots'),
        (8, (0.3, 0.2), 'low < high'),
        (8, (0.1, 0.8), 'low < high'),  # 0.8 > pi/4 = 0.785: wider than a slot
        (8, (-0.1, 0.2), 'low < high'),
    ],
)
def test_when_the_switch_model_is_inconsistent_expect_a_config_error(slots, window, match):
    with pytest.raises(GpioConfigError, match=match):
        JointPhaseSwitch('trigger', slots, window)


def test_when_an_output_starts_at_half_expect_a_config_error():
    with pytest.raises(GpioConfigError, match='not 0 or 1'):
        PinSpec('laser', PinKind.OUTPUT, initial=0.5)


def test_when_a_command_is_valid_expect_every_write():
    writes = check_command(PINS, ['laser', 'servo'], [1.0, 0.1])
    assert writes == {'laser': 1.0, 'servo': 0.1}


@pytest.mark.parametrize(
    ('names', 'values', 'match'),
    [
        (['servo'], [1.5], r'outside the duty cycle range \[0, 1\]'),
        (['servo'], [-0.01], 'outside the duty cycle range'),
        (['servo'], [math.nan], 'not a finite number'),
        (['laser'], [math.inf], 'not a finite number'),
        (['laser'], [0.5], 'not 0 or 1'),
        (['switch'], [1.0], 'input'),
        (['buzzer'], [1.0], "unknown pin 'buzzer'"),
        (['laser', 'laser'], [1.0, 0.0], 'listed twice'),
        (['laser'], [1.0, 0.0], '1 names but 2 values'),
    ],
)
def test_when_a_command_is_bad_expect_it_rejected_with_the_reason(names, values, match):
    with pytest.raises(GpioCommandError, match=match):
        check_command(PINS, names, values)


def test_when_one_entry_is_bad_expect_nothing_of_the_command_applied():
    with pytest.raises(GpioCommandError, match='servo') as info:
        check_command(PINS, ['laser', 'servo'], [1.0, 2.0])
    assert 'laser' not in str(info.value)  # the good entry is not a problem, just not applied


def test_when_the_duty_cycle_is_at_its_limits_expect_it_accepted():
    assert value_problem(PinKind.PWM, 0.0) is None
    assert value_problem(PinKind.PWM, 1.0) is None


def test_when_a_command_floods_bad_entries_expect_a_short_rejection_with_a_count():
    # The finding: GPIO warnings repeated the whole bad input (log lines of 6-10 MB).
    names = ['x' * 1_000_000] + [f'pin{i}' for i in range(100_000)]
    with pytest.raises(GpioCommandError) as info:
        check_command(PINS, names, [1.0] * len(names))
    text = str(info.value)
    assert len(text) < 1000
    assert '(100001 entries)' in text and 'and 99998 more' in text
