import math

import pytest
from rm_base.errors import ConfigError, InputRejectedError
from rm_plugins.shooter.jam_detector import JamDetector, JamDetectorParams

# Jam: |effort| > 2 N·m and |speed| < 1 rad/s for at least 0.1 s.
PARAMS = JamDetectorParams(effort_threshold=2.0, speed_threshold=1.0, time_s=0.1)
STALLED = (3.0, 0.2)  # effort 3 > 2, speed 0.2 < 1


def test_when_stalled_shorter_than_time_expect_no_jam():
    detector = JamDetector(PARAMS)
    # 9 steps of 0.01 s = 0.09 s < 0.1 s
    assert not any(detector.update(*STALLED, 0.01) for _ in range(9))


def test_when_stalled_for_time_expect_jam():
    detector = JamDetector(PARAMS)
    results = [detector.update(*STALLED, 0.01) for _ in range(10)]
    # The 10th step brings the stall to 10 * 0.01 = 0.1 s (0.09999999999999999 in floats).
    assert results == [False] * 9 + [True]
    assert detector.jammed


def test_when_reversing_into_a_stall_expect_jam():
    detector = JamDetector(PARAMS)
    # Magnitudes: effort -3, speed -0.2 stall just as well (a jam while reversing).
    assert detector.update(-3.0, -0.2, 0.1)


def test_when_speed_recovers_expect_jam_cleared_and_time_restarted():
    detector = JamDetector(PARAMS)
    detector.update(*STALLED, 0.2)
    assert detector.jammed
    assert not detector.update(3.0, 5.0, 0.01)  # moving again
    assert detector.stalled_s == 0.0
    assert not detector.update(*STALLED, 0.05)  # 0.05 s < 0.1 s: counting from zero


def test_when_effort_drops_expect_jam_cleared():
    detector = JamDetector(PARAMS)
    detector.update(*STALLED, 0.2)
    assert not detector.update(0.5, 0.0, 0.01)  # standing still, but not pushing


def test_when_stall_interrupted_expect_time_not_accumulated_across_the_gap():
    detector = JamDetector(PARAMS)
    detector.update(*STALLED, 0.06)
    detector.update(3.0, 2.0, 0.01)
    # 0.06 + 0.06 would be a jam, but the gap restarted the count: 0.06 s.
    assert not detector.update(*STALLED, 0.06)


def test_when_reset_expect_time_forgotten():
    detector = JamDetector(PARAMS)
    detector.update(*STALLED, 0.2)
    detector.reset()
    assert not detector.jammed
    assert detector.stalled_s == 0.0


def test_when_effort_exactly_at_threshold_expect_not_stalled():
    detector = JamDetector(PARAMS)
    # "above" and "below" are strict: effort 2.0 is not above 2.0.
    assert not detector.update(2.0, 0.0, 1.0)


def test_when_time_zero_expect_jam_on_first_stalled_step():
    detector = JamDetector(JamDetectorParams(2.0, 1.0, 0.0))
    assert not detector.jammed
    assert detector.update(*STALLED, 0.001)


@pytest.mark.parametrize(
    ('effort', 'speed', 'dt', 'message'),
    [
        (math.nan, 0.0, 0.01, 'finite'),
        (1.0, math.inf, 0.01, 'finite'),
        (1.0, 0.0, 0.0, 'dt'),
        (1.0, 0.0, -0.01, 'dt'),
        (1.0, 0.0, math.nan, 'dt'),
    ],
)
def test_when_input_invalid_expect_rejected_and_state_kept(effort, speed, dt, message):
    detector = JamDetector(PARAMS)
    detector.update(*STALLED, 0.05)
    with pytest.raises(InputRejectedError, match=message):
        detector.update(effort, speed, dt)
    assert detector.stalled_s == pytest.approx(0.05)


@pytest.mark.parametrize(
    ('kwargs', 'message'),
    [
        ({'effort_threshold': 0.0}, 'effort_threshold'),
        ({'speed_threshold': -1.0}, 'speed_threshold'),
        ({'time_s': -0.1}, 'time_s'),
        ({'time_s': math.nan}, 'time_s'),
    ],
)
def test_when_params_invalid_expect_config_error(kwargs, message):
    values = {'effort_threshold': 2.0, 'speed_threshold': 1.0, 'time_s': 0.1, **kwargs}
    with pytest.raises(ConfigError, match=message):
        JamDetectorParams(**values)
