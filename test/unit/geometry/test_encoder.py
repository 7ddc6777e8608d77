import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry import EncoderUnwrapper, rotor_to_output

RAD_PER_TICK = 2.0 * math.pi / 8192


def test_when_first_sample_expect_single_turn_angle():
    encoder = EncoderUnwrapper()
    # 2048 of 8192 ticks = a quarter turn = pi/2
    assert encoder.update(2048) == pytest.approx(0.5 * math.pi)


def test_when_before_first_sample_expect_no_angle():
    encoder = EncoderUnwrapper()
    assert not encoder.initialized
    assert encoder.angle is None
    assert encoder.single_turn_angle is None


def test_when_crossing_wrap_forwards_expect_continuous_increase():
    encoder = EncoderUnwrapper()
    encoder.update(8000)
    # 8000 -> 100: forward by 8192 - 8000 + 100 = 292 ticks; total 8292 ticks
    assert encoder.update(100) == pytest.approx(8292 * RAD_PER_TICK)
    assert encoder.turns == 1
    assert encoder.single_turn_angle == pytest.approx(100 * RAD_PER_TICK)


def test_when_crossing_wrap_backwards_expect_continuous_decrease():
    encoder = EncoderUnwrapper()
    encoder.update(100)
    # 100 -> 8000: back by 292 ticks; total 100 - 292 = -192 ticks
    assert encoder.update(8000) == pytest.approx(-192 * RAD_PER_TICK)
    assert encoder.turns == -1


def test_when_moving_just_under_half_a_turn_expect_that_direction():
    encoder = EncoderUnwrapper()
    encoder.update(0)
    # +4095 ticks is less than half a turn (4096): taken as forwards
    assert encoder.update(4095) == pytest.approx(4095 * RAD_PER_TICK)


def test_when_moving_exactly_half_a_turn_expect_backwards():
    encoder = EncoderUnwrapper()
    encoder.update(0)
    # +4096 is ambiguous; by convention it counts as -4096
    assert encoder.update(4096) == pytest.approx(-4096 * RAD_PER_TICK)


def test_when_many_turns_expect_exact_count():
    encoder = EncoderUnwrapper()
    encoder.update(0)
    # 1000 turns forward in steps of 4000 ticks: 8192 * 1000 / 4000 = 2048 steps
    ticks = 0
    for _ in range(2048):
        ticks = (ticks + 4000) % 8192
        encoder.update(ticks)
    assert encoder.total_ticks == 8192 * 1000
    assert encoder.turns == 1000


def test_when_resolution_configured_expect_it_used():
    encoder = EncoderUnwrapper(16384)
    encoder.update(16000)
    # 16000 -> 200 with 16384 ticks/rev: +584 ticks; total 16584 = 1 turn + 200 ticks
    assert encoder.update(200) == pytest.approx(16584 * 2.0 * math.pi / 16384)


def test_when_numpy_integer_ticks_expect_accepted():
    assert EncoderUnwrapper().update(np.uint16(4096)) == pytest.approx(math.pi)


@pytest.mark.parametrize('ticks', [-1, 8192, 70000])
def test_when_ticks_out_of_range_expect_rejected(ticks):
    with pytest.raises(InputRejectedError, match=r'0\.\.8191'):
        EncoderUnwrapper().update(ticks)


@pytest.mark.parametrize('ticks', [1.5, math.nan, '12'])
def test_when_ticks_not_integer_expect_rejected(ticks):
    with pytest.raises(InputRejectedError, match='integer'):
        EncoderUnwrapper().update(ticks)


def test_when_ticks_rejected_expect_state_unchanged():
    encoder = EncoderUnwrapper()
    encoder.update(8000)
    with pytest.raises(InputRejectedError):
        encoder.update(9000)
    # Still unwrapping from 8000: -> 100 is +292 ticks
    assert encoder.update(100) == pytest.approx(8292 * RAD_PER_TICK)


def test_when_reset_expect_next_sample_initialises():
    encoder = EncoderUnwrapper()
    encoder.update(8000)
    encoder.update(100)
    encoder.reset()
    # No unwrapping against the old 100: the angle is that of 300 ticks alone
    assert encoder.update(300) == pytest.approx(300 * RAD_PER_TICK)


@pytest.mark.parametrize('ticks_per_rev', [0, 3, 8192.0, True])
def test_when_resolution_invalid_expect_config_error(ticks_per_rev):
    with pytest.raises(ConfigError, match='ticks_per_rev'):
        EncoderUnwrapper(ticks_per_rev)


def test_when_rotor_angle_geared_down_expect_output_angle():
    # M3508: 3591/187 rotor turns per output turn; 2pi * 3591/187 rotor rad -> 2pi output
    assert rotor_to_output(2.0 * math.pi * 3591 / 187, 3591 / 187) == pytest.approx(2.0 * math.pi)


def test_when_gear_ratio_zero_expect_config_error():
    with pytest.raises(ConfigError, match='gear_ratio'):
        rotor_to_output(1.0, 0.0)


@given(
    start=st.integers(min_value=0, max_value=8191),
    steps=st.lists(st.integers(min_value=-4096, max_value=4095), min_size=1, max_size=200),
)
def test_when_steps_below_half_a_turn_expect_angle_follows_true_motion(start, steps):
    # Simulate a shaft moving by known tick steps; the encoder only sees them mod 8192.
    encoder = EncoderUnwrapper()
    true_ticks = start
    encoder.update(start)
    for step in steps:
        true_ticks += step
        angle = encoder.update(true_ticks % 8192)
        assert angle == pytest.approx(true_ticks * RAD_PER_TICK, abs=1e-9)
        assert encoder.total_ticks == true_ticks
