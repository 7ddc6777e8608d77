import math

import pytest
from rm_base.control import LowPassFilter, MovingAverage
from rm_base.errors import ConfigError, InputRejectedError


def test_when_first_sample_expect_filter_initialised_to_it():
    assert LowPassFilter(0.1).update(5.0, 0.01) == 5.0


def test_when_step_for_one_time_constant_expect_63_percent():
    lpf = LowPassFilter(0.1)
    lpf.update(0.0, 0.1)
    # y = 0 + (1 - 0) * (1 - exp(-0.1 / 0.1)) = 1 - e^-1 = 0.6321206
    assert lpf.update(1.0, 0.1) == pytest.approx(1.0 - math.exp(-1.0))


def test_when_step_split_in_two_expect_same_response():
    lpf = LowPassFilter(0.1)
    lpf.update(0.0, 0.05)
    lpf.update(1.0, 0.05)
    # 1 - e^-0.5 after the first half, then e^-0.5 of the gap closes again:
    # 1 - e^-0.5 * e^-0.5 = 1 - e^-1, the same as one step of 0.1 s
    assert lpf.update(1.0, 0.05) == pytest.approx(1.0 - math.exp(-1.0))


def test_when_built_from_cutoff_expect_time_constant():
    # tau = 1 / (2 pi fc); fc = 1 / (2 pi) Hz -> tau = 1 s
    assert LowPassFilter.from_cutoff_hz(1.0 / (2.0 * math.pi)).time_constant_s == pytest.approx(1.0)


def test_when_reset_expect_next_sample_initialises():
    lpf = LowPassFilter(0.1)
    lpf.update(1.0, 0.01)
    lpf.reset()
    assert lpf.value is None
    assert lpf.update(7.0, 0.01) == 7.0


@pytest.mark.parametrize(('sample', 'dt'), [(math.nan, 0.01), (1.0, 0.0), (math.inf, 0.01)])
def test_when_filter_input_invalid_expect_rejected(sample, dt):
    with pytest.raises(InputRejectedError):
        LowPassFilter(0.1).update(sample, dt)


@pytest.mark.parametrize('tau', [0.0, -1.0, math.nan, math.inf])
def test_when_time_constant_invalid_expect_config_error(tau):
    with pytest.raises(ConfigError, match='time_constant_s'):
        LowPassFilter(tau)


def test_when_window_filling_expect_mean_of_samples_so_far():
    average = MovingAverage(3)
    # 1 -> 1; (1 + 2) / 2 = 1.5; (1 + 2 + 3) / 3 = 2; window full: (2 + 3 + 4) / 3 = 3
    assert [average.update(x) for x in (1.0, 2.0, 3.0, 4.0)] == pytest.approx([1.0, 1.5, 2.0, 3.0])


def test_when_average_sample_nan_expect_rejected_and_not_added():
    average = MovingAverage(2)
    average.update(1.0)
    with pytest.raises(InputRejectedError):
        average.update(math.nan)
    assert average.value == 1.0


@pytest.mark.parametrize('window', [0, -1, 2.5, True])
def test_when_window_invalid_expect_config_error(window):
    with pytest.raises(ConfigError, match='window'):
        MovingAverage(window)
