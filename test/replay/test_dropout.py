"""Replay of test/data/dropout: RAW at 1 m/s, then every command stops (at 2 s).

The chassis must go PASSIVE within its command_timeout of the last /chassis_cmd, the
wheels must be switched off (MODE_OFF, zero output) and the robot coasts to a stop on
the motors' friction: PASSIVE means limp, nothing brakes (rm_plugins.chassis docstring).
Measured (lockstep, the same on every run): PASSIVE 0.253 s after the last command
(timeout 0.25 s); the robot coasts to a stop on the sim's motor friction alone.
"""

from __future__ import annotations

import itertools

import pytest

from replay.scenarios import DROPOUT_AT_S, WHEELS
from rm_msgs.msg import ActuatorCmd, ChassisCmd

pytestmark = [pytest.mark.ros, pytest.mark.slow]

# The first PASSIVE report comes within command_timeout (0.25 s) + 0.02 s of the last
# command's stamp: one plugin period (5 ms) and one report period (10 ms).
PASSIVE_TOLERANCE = 0.02  # [s]
# The bridge applies MODE_OFF from the plugin's next /actuator_cmd: within 0.1 s of the
# PASSIVE report, everything included.
WHEELS_OFF_WITHIN = 0.1  # [s]
STOPPED = 0.02  # [m/s] at rest


def stamp_ns(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def timed_out(result):
    """(last /chassis_cmd sent, first ChassisState after it that reports the timeout).

    The report that names the timeout is the one looked for (a PASSIVE for another
    reason, such as stale wheel feedback, would not count).
    """
    last = result.last_sent('/chassis_cmd')
    after = [s for s in result.samples('/chassis_state') if stamp_ns(s.msg) > last.stamp_ns]
    timeout = next(
        s
        for s in after
        if s.msg.state == ChassisCmd.PASSIVE and 'no command on /chassis_cmd' in s.msg.reason
    )
    return last, timeout


def test_when_commands_stop_expect_passive_within_the_command_timeout(replayed):
    result = replayed('dropout')
    info = f'{result.summary()} -> {result.output}'
    timeout = result.parameters['rm_robot']['chassis.command_timeout']
    last, passive = timed_out(result)
    delay = (stamp_ns(passive.msg) - last.stamp_ns) * 1e-9
    print(
        f'dropout: last command at {last.t:.3f} s, PASSIVE {delay:.3f} s later: '
        f'{passive.msg.reason!r}'
    )
    assert last.bag_t == pytest.approx(DROPOUT_AT_S, abs=0.03), info
    assert timeout - 0.01 <= delay <= timeout + PASSIVE_TOLERANCE, info
    # ... and it stays PASSIVE to the end.
    after = [s.msg.state for s in result.samples('/chassis_state') if s.t >= passive.t]
    assert set(after) == {ChassisCmd.PASSIVE}, info


def test_when_commands_stop_expect_the_wheels_off_and_the_robot_coasting_to_a_stop(replayed):
    result = replayed('dropout')
    info = f'{result.summary()} -> {result.output}'
    _, passive = timed_out(result)
    later = [
        s.msg for s in result.samples('/actuator_states') if s.t > passive.t + WHEELS_OFF_WITHIN
    ]
    assert later, info
    for msg in later:
        index = [list(msg.name).index(w) for w in WHEELS]
        assert all(msg.mode[i] == ActuatorCmd.MODE_OFF for i in index), info
        assert all(msg.command[i] == 0.0 for i in index), info
    # Limp wheels: the robot slows on friction alone, never speeds up, and stops.
    coasting = result.body_between(passive.t)
    speeds = [s.vx for s in coasting]
    assert all(b <= a + 0.01 for a, b in itertools.pairwise(speeds)), info
    final = result.body[-1]
    stopped = next((s for s in coasting if abs(s.vx) < STOPPED), None)
    print(
        f'coast: from {speeds[0]:.2f} m/s at {coasting[0].t:.2f} s over '
        f'{final.x - coasting[0].x:.2f} m, stopped at {stopped.t if stopped else None} s'
    )
    assert abs(final.vx) < STOPPED and abs(final.vy) < STOPPED, info
