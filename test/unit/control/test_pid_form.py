"""A loop's PID form from its config: positional (default) or incremental with a TD."""

import pytest
from rm_base.control import (
    IncrementalPid,
    IncrementalPidConfig,
    IncrementalPidGains,
    Pid,
    PidGains,
    TdParams,
    build_pid,
    pid_config,
)
from rm_base.errors import ConfigError


def test_positional_is_the_default_form():
    assert pid_config({'kp': 2.0, 'integral_limit': 1.0}) == PidGains(kp=2.0, integral_limit=1.0)
    assert pid_config({'form': 'positional', 'kp': 2.0}) == PidGains(kp=2.0)
    assert pid_config(None) == PidGains()
    assert isinstance(build_pid(PidGains(kp=1.0)), Pid)


def test_incremental_with_and_without_a_tracking_differentiator():
    plain = pid_config({'form': 'incremental', 'kp': 1.0, 'ki': 0.5, 'output_limit': 3.0})
    assert plain == IncrementalPidConfig(IncrementalPidGains(1.0, 0.5, 0.0, 3.0))
    with_td = pid_config({'form': 'incremental', 'kp': 1.0, 'td_acceleration_limit': 40.0,
                          'td_filter_factor': 0.005})
    assert with_td.setpoint_td == TdParams(40.0, 0.005)
    controller = build_pid(with_td)
    assert isinstance(controller, IncrementalPid)
    # the same numbers as the incremental PID built by hand
    by_hand = IncrementalPid(IncrementalPidGains(kp=1.0), TdParams(40.0, 0.005))
    for step in range(5):
        assert controller.update(10.0, step * 0.1, 0.001) == by_hand.update(10.0, step * 0.1, 0.001)


@pytest.mark.parametrize(
    ('data', 'message'),
    [
        ({'form': 'velocity'}, "form must be 'positional' or 'incremental'"),
        ({'form': 'incremental', 'integral_limit': 1.0}, 'unknown key'),
        ({'kp': 1.0, 'td_acceleration_limit': 5.0}, 'unknown key'),
        ({'form': 'incremental', 'td_filter_factor': 0.01}, 'needs td_acceleration_limit'),
        ({'form': 'incremental', 'kp': -1.0}, 'kp'),
        ({'form': 'incremental', 'td_acceleration_limit': 0.0}, 'acceleration_limit'),
    ],
)
def test_a_bad_loop_config_is_refused_naming_the_problem(data, message):
    with pytest.raises(ConfigError, match=message):
        pid_config(data)
