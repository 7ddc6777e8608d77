"""LiveGains: a joint's loop gains checked whole, queued, and applied between two ticks."""

import pytest
from rm_base.bridge.live_gains import LiveGains
from rm_base.config.schema import InvalidValueError
from rm_base.control import IncrementalPidConfig, PidGains

KP = 'joints.wheel.velocity_pid.kp'


class Wheel:
    def __init__(self):
        self.applied = []

    def set_loop_gains(self, velocity=None, position=None):
        self.applied.append((velocity, position))


@pytest.fixture
def live():
    wheel = Wheel()
    gains = LiveGains({'wheel': wheel, 'yaw': Wheel()}, {
        'wheel': {'velocity_pid': PidGains(kp=1.0, output_limit=10.0),
                  'position_pid': PidGains()},
        'yaw': {'velocity_pid': IncrementalPidConfig(), 'position_pid': PidGains()},
    })
    return gains, wheel


def test_a_call_is_applied_whole_at_the_next_tick_not_before(live):
    gains, wheel = live
    gains.propose({KP: 2.5, 'joints.wheel.velocity_pid.ki': 0.5})
    assert wheel.applied == []  # queued: nothing between two ticks
    assert gains(0, 0.001) is True
    ((velocity, position),) = wheel.applied
    assert (velocity.kp, velocity.ki, velocity.output_limit, position) == (2.5, 0.5, 10.0, None)
    assert gains(1, 0.001) is False  # nothing queued: not timed
    gains.propose({'joints.wheel.velocity_pid.kd': 0.1})  # builds on what was applied
    gains(2, 0.001)
    assert (wheel.applied[-1][0].kp, wheel.applied[-1][0].kd) == (2.5, 0.1)


@pytest.mark.parametrize(('values', 'match'), [
    ({KP: -1.0}, r'joints\.wheel\.velocity_pid: .*kp'),
    ({KP: 'fast'}, rf'{KP} must be a number'),
    ({KP: float('nan')}, rf'{KP} must not be NaN'),
    ({KP: float('inf')}, r'joints\.wheel\.velocity_pid: PidGains\.kp must be finite'),
    ({'joints.wheel.velocity_pid.angle_mode': True}, 'needs a restart'),
    ({'joints.yaw.velocity_pid.kp': 1.0}, 'not a positional PID'),
    ({'joints.nobody.velocity_pid.kp': 1.0}, "no joint 'nobody'"),
])
def test_a_bad_value_refuses_the_whole_call_naming_the_key(live, values, match):
    gains, wheel = live
    with pytest.raises(InvalidValueError, match=match):
        gains.propose({'joints.wheel.velocity_pid.ki': 0.5, **values})
    assert gains(0, 0.001) is False and wheel.applied == []


def test_a_limit_may_be_switched_off_live_as_at_start_up(live):
    gains, wheel = live
    gains.propose({'joints.wheel.velocity_pid.output_limit': float('inf')})
    gains(0, 0.001)
    assert wheel.applied[-1][0].output_limit == float('inf')


def test_only_joint_loop_keys_are_taken():
    assert LiveGains.takes(KP)
    assert not LiveGains.takes('joints.wheel.id')
    assert not LiveGains.takes('publish_rate')
