"""Safety rules of the actuator base: every one ends with a zero command."""

import math

import can
import pytest
from rm_base.hardware.actuators import HoldReason, Mode
from rm_base.hardware.config import SafetyConfig
from rm_base.hardware.errors import CommandRejectedError
from rm_base.motors import actuator_class
from rm_base.motors.dji import protocol as dji
from support.hardware import MS, T0, joint

ONE_NM_RAW = 2731  # 1 N·m / 0.3 N·m/A * 16384/20 (M3508)


def make(safety=None, **extra):
    cfg = joint(**extra)
    return actuator_class(cfg.type)(cfg, safety)


def feed(a, now_ns, temperature=30):
    msg = can.Message(arbitration_id=a.feedback_id, data=dji.encode_feedback(0, 0, 0, temperature))
    a.handle_frame(msg, now_ns)


def step(a, now_ns):
    a.update(now_ns, 0.001)
    return a.command_raw


def running(safety=None, **extra):
    a = make(safety, **extra)
    feed(a, T0)
    a.set_command(Mode.EFFORT, T0, effort=1.0)
    assert step(a, T0) == ONE_NM_RAW
    return a


def test_no_feedback_yet_means_offline_and_zero():
    a = make()
    a.set_command(Mode.EFFORT, T0, effort=1.0)
    assert step(a, T0) == 0
    assert a.hold_reason is HoldReason.OFFLINE
    assert not a.state().online


def test_feedback_older_than_the_timeout_means_offline_and_zero():
    a = running()
    a.set_command(Mode.EFFORT, T0 + 100 * MS, effort=1.0)
    assert step(a, T0 + 100 * MS) == ONE_NM_RAW  # exactly 100 ms old: still online
    a.set_command(Mode.EFFORT, T0 + 101 * MS, effort=1.0)
    assert step(a, T0 + 101 * MS) == 0
    assert a.hold_reason is HoldReason.OFFLINE
    assert a.state().online is False
    assert a.state().mode == Mode.OFF
    feed(a, T0 + 102 * MS)  # feedback again: output resumes with the fresh command
    a.set_command(Mode.EFFORT, T0 + 102 * MS, effort=1.0)
    assert step(a, T0 + 102 * MS) == ONE_NM_RAW


def test_feedback_timeout_is_configurable():
    a = running(SafetyConfig(feedback_timeout_s=0.02))
    a.set_command(Mode.EFFORT, T0 + 21 * MS, effort=1.0)
    assert step(a, T0 + 21 * MS) == 0


def test_no_command_for_the_timeout_means_zero():
    a = running()
    feed(a, T0 + 100 * MS)
    assert step(a, T0 + 100 * MS) == ONE_NM_RAW
    feed(a, T0 + 101 * MS)
    assert step(a, T0 + 101 * MS) == 0
    assert a.hold_reason is HoldReason.COMMAND_TIMEOUT


def test_never_commanded_means_zero():
    a = make()
    feed(a, T0)
    assert step(a, T0) == 0
    assert a.hold_reason is HoldReason.NO_COMMAND


def test_over_temperature_holds_zero_with_hysteresis():
    a = running(temperature_limit=70.0)
    for temperature, raw in ((70, 0), (66, 0), (65, 0), (64, ONE_NM_RAW)):
        # resumes only below 70 - 5 = 65 degC
        now = a.feedback.stamp_ns + MS
        feed(a, now, temperature=temperature)
        a.set_command(Mode.EFFORT, now, effort=1.0)
        assert step(a, now) == raw, temperature


def test_over_temperature_reason_is_reported():
    a = running(temperature_limit=70.0)
    feed(a, T0 + MS, temperature=90)
    step(a, T0 + MS)
    assert a.hold_reason is HoldReason.OVER_TEMPERATURE
    assert a.state().temperature == 90.0


@pytest.mark.parametrize('field', ['position', 'velocity', 'effort', 'kp', 'kd'])
@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_nan_and_inf_are_rejected_and_the_last_safe_target_stays(field, bad):
    a = running()
    with pytest.raises(CommandRejectedError, match=f'{field} is'):
        a.set_command(Mode.EFFORT, T0 + MS, **{field: bad})
    assert a.commands_rejected == 1
    assert a.last_rejection.startswith(field)
    feed(a, T0 + MS)
    assert step(a, T0 + MS) == ONE_NM_RAW  # the previous target, still fresh
    # and it times out like any other target
    feed(a, T0 + 101 * MS)
    assert step(a, T0 + 101 * MS) == 0


@pytest.mark.parametrize(
    ('kwargs', 'match'),
    [
        ({'mode': 7}, 'unknown mode 7'),
        ({'mode': Mode.MIT, 'kp': -1.0}, 'gains must be >= 0'),
        ({'mode': Mode.EFFORT, 'effort': '1'}, 'must be a number'),
    ],
)
def test_other_invalid_commands_are_rejected(kwargs, match):
    a = running()
    with pytest.raises(CommandRejectedError, match=match):
        a.set_command(now_ns=T0, **kwargs)
    assert a.command.mode is Mode.EFFORT


def test_bus_failure_holds_zero_until_back_and_commanded_again():
    a = running()
    a.notify_bus_down(T0 + MS)
    feed(a, T0 + MS)
    a.set_command(Mode.EFFORT, T0 + MS, effort=1.0)  # commands keep coming while down
    assert step(a, T0 + MS) == 0
    assert a.hold_reason is HoldReason.BUS_RECOVERY
    a.notify_bus_recovered(T0 + 2 * MS)
    feed(a, T0 + 2 * MS)
    assert step(a, T0 + 2 * MS) == 0  # the command from before the recovery is not resumed
    a.set_command(Mode.EFFORT, T0 + 3 * MS, effort=1.0)
    assert step(a, T0 + 3 * MS) == ONE_NM_RAW


def test_bus_recovery_sends_zero_at_least_once_even_with_a_newer_command():
    a = running()
    a.notify_bus_down(T0 + MS)
    a.notify_bus_recovered(T0 + 2 * MS)
    feed(a, T0 + 3 * MS)
    a.set_command(Mode.EFFORT, T0 + 3 * MS, effort=1.0)  # already newer than the recovery
    assert step(a, T0 + 3 * MS) == 0
    assert step(a, T0 + 3 * MS) == ONE_NM_RAW


def test_shutdown_holds_zero():
    a = running()
    a.shutdown()
    feed(a, T0 + MS)
    a.set_command(Mode.EFFORT, T0 + MS, effort=1.0)
    assert step(a, T0 + MS) == 0
    assert a.hold_reason is HoldReason.SHUTDOWN


def test_an_exception_in_update_holds_zero_and_is_counted():
    class Breaking(actuator_class(joint().type)):
        broken = False

        def _set_output(self, *args):
            if self.broken:
                raise RuntimeError('bug')
            return super()._set_output(*args)

    a = Breaking(joint(), None)
    feed(a, T0)
    a.set_command(Mode.EFFORT, T0, effort=1.0)
    assert step(a, T0) == ONE_NM_RAW
    Breaking.broken = True
    feed(a, T0 + MS)
    a.set_command(Mode.EFFORT, T0 + MS, effort=1.0)
    assert step(a, T0 + MS) == 0
    assert a.hold_reason is HoldReason.ERROR
    assert a.update_errors == 1


def test_every_output_is_clamped_to_max_effort_in_every_mode():
    # 1.5 N·m / 0.3 = 5 A -> 4096 raw
    a = running(max_effort=1.5, velocity_pid={'kp': 1e3}, position_pid={'kp': 1e3})
    cases = [
        {'mode': Mode.EFFORT, 'effort': -50.0},
        {'mode': Mode.VELOCITY, 'velocity': 40.0},
        {'mode': Mode.POSITION, 'position': -40.0},
        {'mode': Mode.MIT, 'position': 40.0, 'kp': 1e3},
    ]
    for k, c in enumerate(cases, 1):
        now = T0 + k * MS
        feed(a, now)
        a.set_command(now_ns=now, **c)
        assert abs(step(a, now)) == 4096, c
        assert abs(a.state().command) <= 1.5
