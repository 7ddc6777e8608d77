"""When a DR16 is believed (rm_base.hardware.protocols.dbus.DbusTrust), and noise is not."""

import random

import pytest
from rm_base.hardware.errors import ProtocolError
from rm_base.hardware.protocols import dbus

MS = 1_000_000
PERIOD = 14 * MS


def stream(trust, frames, start_ns=0, period_ns=PERIOD):
    """Feed frames period_ns apart; return what accept said of each."""
    return [trust.accept(f, start_ns + k * period_ns) for k, f in enumerate(frames)]


def test_a_remote_is_believed_from_its_third_frame_in_rhythm():
    trust = dbus.DbusTrust(0.1)
    assert stream(trust, [dbus.DbusFrame()] * 5) == [False, False, True, True, True]
    assert trust.believed and trust.noise_frames == 0


def test_after_a_gap_longer_than_the_timeout_it_must_earn_trust_again():
    trust = dbus.DbusTrust(0.1)
    stream(trust, [dbus.DbusFrame()] * 3)
    assert stream(trust, [dbus.DbusFrame()] * 3, start_ns=3 * PERIOD + 200 * MS) == [
        False, False, True]


def test_a_frame_sooner_than_half_a_period_is_noise_and_dropped():
    trust = dbus.DbusTrust(0.1)
    stream(trust, [dbus.DbusFrame()] * 3)
    assert not trust.accept(dbus.DbusFrame(), 2 * PERIOD + 3 * MS)
    assert trust.noise_frames == 1
    assert trust.accept(dbus.DbusFrame(), 3 * PERIOD)  # the remote's own next frame


def test_a_frame_that_jumps_every_channel_at_once_is_noise():
    trust = dbus.DbusTrust(0.1)
    stream(trust, [dbus.DbusFrame()] * 3)
    jump = dbus.DbusFrame(channels=(600, -600, 600, -600), wheel=500)
    assert not trust.accept(jump, 3 * PERIOD)
    assert trust.noise_frames == 1
    # a stick flicked across its range alone is a hand, not noise
    assert trust.accept(dbus.DbusFrame(channels=(660, 0, 0, 0)), 4 * PERIOD)


def test_noise_before_trust_starts_the_count_again():
    trust = dbus.DbusTrust(0.1)
    good = dbus.DbusFrame()
    assert stream(trust, [good, good]) == [False, False]
    assert not trust.accept(dbus.DbusFrame(channels=(600, 600, 600, 600), wheel=600), 2 * PERIOD)
    assert stream(trust, [good] * 3, start_ns=3 * PERIOD) == [False, False, True]


@pytest.mark.parametrize('buttons', [(2, 0), (0, 0x80), (255, 255)])
def test_mouse_buttons_other_than_0_or_1_do_not_decode(buttons):
    data = bytearray(dbus.encode(dbus.DbusFrame()))
    data[12], data[13] = buttons
    with pytest.raises(ProtocolError, match='mouse buttons'):
        dbus.decode(bytes(data))


def test_ten_thousand_random_bursts_in_perfect_rhythm_are_never_believed():
    # The finding: about 1 in 376 random bursts decoded, and one drove the robot.
    rng = random.Random(42)
    trust = dbus.DbusTrust(0.1)
    decoded = believed = 0
    for k in range(10_000):
        try:
            frame = dbus.decode(rng.randbytes(dbus.FRAME_LENGTH))
        except ProtocolError:
            continue
        decoded += 1
        believed += trust.accept(frame, k * PERIOD)
    assert believed == 0
    assert decoded < 5  # the mouse-button check: ~1 in 24 million decodes now
