"""The step figures against responses whose figures are known in closed form."""

import math

import pytest
from rm_base.control.step_response import StepError, step_figures

DT = 0.0005  # [s] sampling: fine enough that interpolation errors stay below 1e-3 of tau


def sampled(f, duration):
    t = [i * DT for i in range(int(duration / DT) + 1)]
    return t, [f(x) for x in t]


def test_a_first_order_lag_rises_in_tau_ln9_settles_in_tau_ln50_and_does_not_overshoot():
    tau, y0, r = 0.1, 0.2, 0.7  # a 0.5 rad step from 0.2
    t, y = sampled(lambda x: r + (y0 - r) * math.exp(-x / tau), 1.5)
    f = step_figures(t, y, r)
    assert f.rise_time == pytest.approx(tau * math.log(9), rel=1e-3)
    assert f.settling_time == pytest.approx(tau * math.log(50), abs=DT)
    assert f.overshoot_pct == 0.0
    assert f.steady_state_error == pytest.approx(0.0, abs=1e-5)


@pytest.mark.parametrize('zeta', [0.3, 0.5, 0.7])
def test_a_second_order_response_overshoots_by_exp_of_minus_zeta_pi_over_root(zeta):
    wn = 20.0
    wd = wn * math.sqrt(1 - zeta ** 2)
    phi = math.acos(zeta)

    def y(x):  # unit step from 0 (downwards: the sign of the step must not matter)
        return -(1 - math.exp(-zeta * wn * x) * math.sin(wd * x + phi) / math.sqrt(1 - zeta ** 2))

    t, ys = sampled(y, 3.0)
    f = step_figures(t, ys, -1.0)
    assert f.overshoot_pct == pytest.approx(
        100 * math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2)), rel=1e-3)
    assert f.steady_state_error == pytest.approx(0.0, abs=1e-4)
    assert f.settling_time is not None and f.settling_time > f.rise_time > 0


def test_a_response_that_never_arrives_has_no_rise_or_settling_time_and_its_error():
    t, y = sampled(lambda x: 0.5 * (1 - math.exp(-x / 0.05)), 1.0)  # stalls at half
    f = step_figures(t, y, 1.0)
    assert f.rise_time is None and f.settling_time is None
    assert f.steady_state_error == pytest.approx(0.5, abs=1e-6)


@pytest.mark.parametrize(('t', 'y', 'target', 'says'), [
    ([0.0, 0.1], [0.0, 1.0], 1.0, '3 or more samples'),
    ([0.0, 0.1, 0.1], [0.0, 0.5, 1.0], 1.0, 'increase'),
    ([0.0, 0.1, 0.2], [0.0, math.nan, 1.0], 1.0, 'finite'),
    ([0.0, 0.1, 0.2], [1.0, 1.0, 1.0], 1.0, 'no step'),
])
def test_a_record_without_a_step_response_is_refused_saying_why(t, y, target, says):
    with pytest.raises(StepError, match=says):
        step_figures(t, y, target)
