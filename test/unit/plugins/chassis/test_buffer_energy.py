"""power_budget: spend the buffer above the reserve, refill it below, never past the boost."""

import math

import pytest
from rm_base.errors import ConfigError, InputRejectedError
from rm_plugins.chassis.buffer_energy import BufferEnergyParams, power_budget

PARAMS = BufferEnergyParams(reserve_j=20.0, gain_w_per_j=2.0, max_boost_w=60.0)


@pytest.mark.parametrize(
    ('buffer_j', 'expected_w'),
    [
        (20.0, 45.0),  # at the reserve: the limit
        (30.0, 65.0),  # 10 J above: +20 W to spend it
        (60.0, 105.0),  # full: 45 + 2 x 40 = 125, capped at limit + boost = 105
        (10.0, 25.0),  # 10 J under: 20 W under the limit, so it refills
        (0.0, 5.0),
    ],
)
def test_the_budget_follows_the_buffer(buffer_j, expected_w):
    assert power_budget(45.0, buffer_j, PARAMS) == expected_w


def test_the_budget_is_never_negative():
    assert power_budget(10.0, 0.0, PARAMS) == 0.0  # 10 + 2 x (0 - 20) = -30


def test_bad_input_is_refused():
    with pytest.raises(InputRejectedError):
        power_budget(math.nan, 30.0, PARAMS)
    with pytest.raises(InputRejectedError):
        power_budget(-1.0, 30.0, PARAMS)
    with pytest.raises(ConfigError, match='gain_w_per_j'):
        BufferEnergyParams(gain_w_per_j=-1.0)
