"""The simulated GPIO backend: outputs read back, inputs from their models."""

import math

from rm_plugins.gpio import (
    ConstantInput,
    JointPhaseSwitch,
    PinKind,
    PinSpec,
    SimGpioBackend,
)

PINS = {
    'switch': PinSpec('switch', PinKind.INPUT, sim=JointPhaseSwitch('trigger', 8, (0.2, 0.5))),
    'button': PinSpec('button', PinKind.INPUT, sim=ConstantInput(1.0)),
    'laser': PinSpec('laser', PinKind.OUTPUT, initial=1.0),
    'servo': PinSpec('servo', PinKind.PWM, initial=0.075),
}


def test_when_outputs_are_written_expect_them_read_back():
    backend = SimGpioBackend(PINS, lambda joint: None)
    assert backend.read('laser') == 1.0  # initial
    assert backend.read('servo') == 0.075
    backend.write('laser', 0.0)
    backend.write('servo', 0.1)
    assert backend.read('laser') == 0.0
    assert backend.read('servo') == 0.1


def test_when_reset_expect_the_initial_values_back():
    backend = SimGpioBackend(PINS, lambda joint: None)
    backend.write('laser', 0.0)
    backend.reset_outputs()
    assert backend.read('laser') == 1.0


def test_when_the_trigger_turns_expect_the_switch_to_follow_its_phase():
    position = {'trigger': 0.0}
    backend = SimGpioBackend(PINS, position.get)
    assert backend.read('switch') == 0.0  # phase 0: between pockets
    position['trigger'] = 0.3 + 2 * math.pi / 8  # one slot on, phase 0.3
    assert backend.read('switch') == 1.0


def test_when_the_joint_was_never_seen_expect_the_switch_open():
    backend = SimGpioBackend(PINS, lambda joint: None)
    assert backend.read('switch') == 0.0


def test_when_an_input_is_constant_expect_its_value():
    backend = SimGpioBackend(PINS, lambda joint: None)
    assert backend.read('button') == 1.0
