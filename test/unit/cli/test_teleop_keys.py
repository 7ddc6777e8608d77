"""The terminal keyboard as the operator's hands: bytes and times -> what is held."""

import pytest
from rm_base.hardware.protocols.dbus import Key, Switch
from rm_bringup.cli.teleop import describe, frame_of
from rm_bringup.cli.teleop_keys import (
    FIRST_HOLD_S,
    MOUSE_COUNTS,
    REPEAT_HOLD_S,
    Hands,
    TerminalKeys,
)
from rm_plugins.manual.driver import ManualDriver, OperatorInput
from rm_plugins.manual.mapping import load_mapping

W, S, A, D, SHIFT, CTRL, R = (int(k) for k in (Key.W, Key.S, Key.A, Key.D, Key.SHIFT, Key.CTRL,
                                                Key.R))


def held_after(typed, at):
    """Feed (bytes, time) pairs; the hands at time at."""
    keys = TerminalKeys()
    for data, t in typed:
        keys.feed(data, t)
    return keys.hands(at)


@pytest.mark.parametrize(('typed', 'at', 'keys', 'mouse', 'left'), [
    ([(b'w', 0.0)], 0.1, W, (0, 0), False),
    ([(b'W', 0.0)], 0.1, W | SHIFT, (0, 0), False),
    ([(b'\x17', 0.0)], 0.1, W | CTRL, (0, 0), False),  # Ctrl+W
    ([(b'wd', 0.0)], 0.1, W | D, (0, 0), False),
    ([(b'q', 0.0)], 0.1, 0, (-MOUSE_COUNTS, 0), False),  # Q/E are the mouse sideways
    ([(b'e', 0.0)], 0.1, 0, (MOUSE_COUNTS, 0), False),
    ([(b'\x1b[A', 0.0)], 0.1, 0, (0, -MOUSE_COUNTS), False),  # up: the mouse up
    ([(b'\x1bOB', 0.0)], 0.1, 0, (0, MOUSE_COUNTS), False),  # application-mode down
    ([(b'\x1b[D\x1b[C', 0.0)], 0.1, 0, (0, 0), False),  # left and right cancel
    ([(b' ', 0.0)], 0.1, 0, (0, 0), True),
    ([(b'\x1b[', 0.0), (b'C', 0.01)], 0.1, 0, (MOUSE_COUNTS, 0), False),  # split read
    ([(b'1.\x1b9', 0.0)], 0.1, 0, (0, 0), False),  # no keys of ours
])
def test_bytes_become_keys_mouse_and_button(typed, at, keys, mouse, left):
    hands = held_after(typed, at)
    assert (hands.keys, (hands.mouse_x, hands.mouse_y), hands.mouse_left) == (keys, mouse, left)


def test_a_tap_holds_the_key_past_the_repeat_delay_then_lets_go():
    assert held_after([(b'w', 0.0)], FIRST_HOLD_S - 0.01).keys == W
    assert held_after([(b'w', 0.0)], FIRST_HOLD_S + 0.01).keys == 0


def test_a_repeating_key_is_held_until_shortly_after_its_last_repeat():
    typed = [(b'w', 0.0), (b'w', 0.5), (b'w', 0.53), (b'w', 0.56)]
    assert held_after(typed, 0.56 + REPEAT_HOLD_S - 0.01).keys == W
    assert held_after(typed, 0.56 + REPEAT_HOLD_S + 0.01).keys == 0  # before FIRST_HOLD_S ends


def test_p_toggles_passive_on_a_press_not_on_its_repeats():
    keys = TerminalKeys()
    for t in (0.0, 0.5, 0.53, 0.56):
        keys.feed(b'p', t)
    assert keys.hands(0.6).passive
    keys.feed(b'p', 2.0)
    assert not keys.hands(2.1).passive


def test_bytes_that_are_no_key_are_counted():
    keys = TerminalKeys()
    keys.feed(b'1\x1bx\x7f', 0.0)
    assert keys.ignored == 3  # '1', a lone ESC, DEL ('x' is a key)


def test_the_frame_puts_the_right_switch_where_the_mapping_says_and_the_mapping_drives():
    mapping = load_mapping()
    frame = frame_of(Hands(keys=W | SHIFT, mouse_x=MOUSE_COUNTS), mapping)
    assert getattr(frame, mapping.right_switch) is Switch.UP
    assert getattr(frame, mapping.left_switch) is Switch.MID
    commands = ManualDriver(mapping).commands(OperatorInput.from_dbus(frame, mapping))
    assert describe(frame, mapping, commands) == (
        'right UP keys W+SHIFT mouse +100,+0 -> chassis FOLLOW FAST v +2.0 +0.0 | '
        'gimbal RATE yaw -2.0 pitch +0.0 | shooter PASSIVE')
    down = frame_of(Hands(passive=True, keys=W), mapping)
    assert getattr(down, mapping.right_switch) is Switch.DOWN
    commands = ManualDriver(mapping).commands(OperatorInput.from_dbus(down, mapping))
    assert describe(down, mapping, commands).endswith(
        '-> chassis PASSIVE NORMAL v +0.0 +0.0 | gimbal PASSIVE yaw +0.0 pitch +0.0 | '
        'shooter PASSIVE')



class _Publisher:
    def __init__(self, counts):
        self._counts = iter(counts)

    def get_subscription_count(self):
        return next(self._counts)


def test_teleop_waits_for_a_subscriber_then_takes_keys_or_gives_up_at_the_timeout():
    from rm_bringup.cli.ros_node import wait_until_heard

    now = [0.0]

    def sleep(s):
        now[0] += s

    def clock():
        return now[0]

    assert wait_until_heard([_Publisher([0, 0, 1])], 1.0, sleep=sleep, clock=clock)
    assert now[0] == pytest.approx(0.1)
    now[0] = 0.0
    never = _Publisher(iter(lambda: 0, 1))
    assert not wait_until_heard([never], 1.0, sleep=sleep, clock=clock)
    assert 1.0 <= now[0] < 1.1
    now[0] = 0.0  # a stop (bag play's Ctrl-C) ends the wait at once
    assert not wait_until_heard([never], 1.0, stop=lambda: True, sleep=sleep, clock=clock)
    assert now[0] == 0.0
