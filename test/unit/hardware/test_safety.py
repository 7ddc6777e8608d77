"""Safety rules of the actuator base: every one ends with a zero command."""

import math

import can
import pytest
from rm_base.hardware.actuators import HoldReason, Mode
from rm_base.hardware.config import SafetyConfig
from rm_base.hardware.errors import CommandRejectedError
from rm_base.motors import actuator_class
from rm_base.motors.dji import protocol as dji
from rm_base.motors.dji.actuator import M3508
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


def test_a_joint_back_online_stays_held_until_it_has_been_back_for_the_clear_time():
    a = running(SafetyConfig(fault_clear_s=0.5))
    a.set_command(Mode.EFFORT, T0 + 101 * MS, effort=1.0)
    assert step(a, T0 + 101 * MS) == 0  # offline
    now = T0 + 102 * MS
    back = now
    while now < back + 500 * MS:  # one frame is no evidence: 0.5 s of frames is
        feed(a, now)
        a.set_command(Mode.EFFORT, now, effort=1.0)
        assert step(a, now) == 0, (now - back) / MS
        assert a.hold_reason is HoldReason.OFFLINE
        assert a.state().online  # online, but not yet trusted
        now += MS
    feed(a, now)
    a.set_command(Mode.EFFORT, now, effort=1.0)
    assert step(a, now) == ONE_NM_RAW


def test_the_first_feedback_after_start_is_no_fault_to_clear():
    a = make()
    feed(a, T0)
    a.set_command(Mode.EFFORT, T0, effort=1.0)
    assert step(a, T0) == ONE_NM_RAW


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


def drive(a, start_ns, ms, temperature):
    """Feed a frame and a fresh command each ms for ms ms; return the raw commands sent."""
    out = []
    for k in range(ms):
        now = start_ns + k * MS
        feed(a, now, temperature=temperature)
        a.set_command(Mode.EFFORT, now, effort=1.0)
        out.append(step(a, now))
    return out


def warm(a, start_ns, temperatures):
    """Frames stepping through temperatures (each within the plausible step); return end."""
    now = start_ns
    for temperature in temperatures:
        assert set(drive(a, now, 1, temperature)) <= {0, ONE_NM_RAW}
        now += MS
    return now


def test_over_temperature_holds_zero_until_below_the_hysteresis_for_the_clear_time():
    a = running(SafetyConfig(temperature_hysteresis_c=10.0, fault_clear_s=1.0),
                temperature_limit=70.0)
    now = warm(a, T0 + MS, range(30, 71, 4))  # up to 70: the limit
    assert drive(a, now, 1, 70) == [0]
    assert a.hold_reason is HoldReason.OVER_TEMPERATURE
    now = warm(a, now + MS, range(68, 60, -2))  # 60..68: above 70 - 10, still held
    assert set(drive(a, now, 2000, 61)) == {0}
    now += 2000 * MS
    assert drive(a, now, 1, 59) == [0]  # below 60 now: the clear time starts
    held = drive(a, now + MS, 1000, 59)
    assert set(held[:998]) == {0} and held[-1] == ONE_NM_RAW
    assert a.hold_reason is HoldReason.NONE


def test_a_warm_frame_restarts_the_clear_time():
    a = running(SafetyConfig(temperature_hysteresis_c=10.0, fault_clear_s=1.0),
                temperature_limit=70.0)
    now = warm(a, T0 + MS, [*range(30, 71, 4), 70, 66, 62, 58])
    assert set(drive(a, now, 900, 58)) == {0}
    now += 900 * MS
    now = warm(a, now, (61, 58))  # one frame at 61: above 60, the clock starts again
    assert set(drive(a, now, 900, 58)) == {0}
    assert a.hold_reason is HoldReason.OVER_TEMPERATURE


def test_over_temperature_reason_is_reported():
    a = running(temperature_limit=70.0)
    now = warm(a, T0 + MS, range(30, 91, 5))
    step(a, now)
    assert a.hold_reason is HoldReason.OVER_TEMPERATURE
    assert a.state().temperature == 90.0


def test_one_cool_garbage_frame_does_not_lift_an_over_temperature_hold():
    # The finding: wheel_fl at 123 degC, one random frame said 28 degC and it drove.
    a = running(SafetyConfig(fault_clear_s=1.0), temperature_limit=100.0)
    now = warm(a, T0 + MS, range(30, 124, 4))
    assert drive(a, now, 5, 123) == [0] * 5
    now += 5 * MS
    garbage = can.Message(arbitration_id=a.feedback_id,
                          data=bytes.fromhex('049CF45B2D701C97'))
    a.handle_frame(garbage, now)
    a.set_command(Mode.EFFORT, now, effort=1.0)
    assert step(a, now) == 0
    assert a.feedback.temperature == 123  # the garbage never became the joint's feedback
    assert a.implausible_frames == 1
    assert set(drive(a, now + MS, 100, 123)) == {0}
    assert a.hold_reason is HoldReason.OVER_TEMPERATURE


def test_a_temperature_jump_is_implausible_and_holds_for_the_clear_time():
    a = running(SafetyConfig(fault_clear_s=0.2, max_temperature_step_c=5.0))
    assert drive(a, T0 + MS, 1, 36) == [0]  # 30 -> 36 in a ms: no motor does that
    assert a.hold_reason is HoldReason.IMPLAUSIBLE
    assert a.feedback.temperature == 30
    out = drive(a, T0 + 2 * MS, 250, 36)
    assert set(out[:199]) == {0} and set(out[200:]) == {ONE_NM_RAW}
    assert a.feedback.temperature == 36  # consistent frames are believed again


def test_an_angle_jump_of_a_still_shaft_is_implausible():
    a = running(SafetyConfig(fault_clear_s=0.2))
    jump = can.Message(arbitration_id=a.feedback_id, data=dji.encode_feedback(3000, 0, 0, 30))
    a.handle_frame(jump, T0 + MS)
    a.set_command(Mode.EFFORT, T0 + MS, effort=1.0)
    assert step(a, T0 + MS) == 0
    assert a.hold_reason is HoldReason.IMPLAUSIBLE
    assert a.feedback.position == 0.0


def test_a_fast_shaft_may_move_far_between_frames():
    a = running()
    for k, ticks in enumerate((2000, 4000, 6000)):  # 6000 rpm: 0.6 turn a ms
        msg = can.Message(arbitration_id=a.feedback_id,
                          data=dji.encode_feedback(ticks, 6000, 0, 30))
        a.handle_frame(msg, T0 + (k + 1) * MS)
    assert a.implausible_frames == 0


class _ErrorByte(M3508):
    """An M3508 whose unused last byte is an error code (a family that reports one)."""

    def _decode(self, msg):
        angle, velocity, torque, temperature, _ = super()._decode(msg)
        return angle, velocity, torque, temperature, msg.data[7]


def test_a_device_fault_latches_for_the_clear_time():
    a = _ErrorByte(joint(), SafetyConfig(fault_clear_s=0.1))
    drive(a, T0, 1, 30)
    data = bytearray(dji.encode_feedback(0, 0, 0, 30))
    data[7] = 3
    a.handle_frame(can.Message(arbitration_id=a.feedback_id, data=bytes(data)), T0 + MS)
    a.set_command(Mode.EFFORT, T0 + MS, effort=1.0)
    assert step(a, T0 + MS) == 0
    assert a.hold_reason is HoldReason.DEVICE_FAULT
    out = drive(a, T0 + 2 * MS, 120, 30)  # no error from here: held 100 ms more
    assert set(out[:99]) == {0} and set(out[100:]) == {ONE_NM_RAW}


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


def test_a_flapping_link_is_said_once_a_second_with_a_count():
    # The finding: offline/online storms of 27 lines every few seconds.
    import logging

    said = []
    handler = logging.Handler()
    handler.emit = lambda record: said.append(record.getMessage())
    logger = logging.getLogger('rm_base.hardware.actuators.base')
    logger.addHandler(handler)
    level = logger.level
    logger.setLevel(logging.INFO)  # setLevel, not .level: it clears the enabled-for cache
    try:
        a = running()
        now = T0
        for _ in range(10):  # silent 101 ms, then a frame: offline, online, ten times
            now += 101 * MS
            step(a, now)
            feed(a, now + MS)
            now += MS
            step(a, now)
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    link = [m for m in said if 'offline' in m or 'online' in m]
    assert len(link) == 1, link  # the first change; the others counted for the next line
    assert a._link_unsaid >= 19
    assert a.hold_reason is HoldReason.OFFLINE  # held all along: back, but not yet trusted
