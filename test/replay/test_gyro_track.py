"""Replay of test/data/gyro_track: GYRO spin in place while the gimbal TRACKs a point.

The robot (imu, chassis and gimbal plugins of standard.yaml on rm_sim; the sim wheels
carrying a 16 kg robot) stands for 2.5 s while the gimbal turns onto a point 3.6 m away
in odom, spins in GYRO for 4.5 s, then stops. The aim is judged on the sim's ground
truth: the barrel's world heading (chassis yaw + yaw joint angle) against the bearing
of the point from the robot.
"""

from __future__ import annotations

import math

import pytest

from replay.scenarios import GYRO_END_S, GYRO_START_S, GYRO_STOP_END_S, TRACK_TARGET
from rm_msgs.msg import GimbalCmd

pytestmark = [pytest.mark.ros, pytest.mark.slow]

# GYRO spins at gyro.spin_rate = 6 rad/s (standard.yaml) standing still; over the 4.5 s
# less the spin-up (~0.3 s at the 20-30 rad/s^2 angular ramp): ~25 rad, 4 turns.
MIN_TURNS = 3.5
SETTLE_S = 1.0  # [s] after GYRO starts (spin-up, then the gimbal's loops catch up)
STATIC_FROM_S = 2.0  # [s] standing, the gimbal has turned onto the point (1.2-1.8 s)
# Aim tolerances, on the sim's ground truth. Standing, the angle loop has nothing to
# follow: measured 0.0000-0.013 rad once settled. Spinning, the gimbal's loops see the
# chassis spin through the IMU and /actuator_states, both a few ms to tens of ms late
# when the process is busy (at 6 rad/s, 10 ms is 0.06 rad): measured on a lightly loaded
# VM (load 2-5, sim at 80-100 % of real time, 10 runs) p90 0.046-0.128 rad, worst
# 0.065-0.29 rad, a steady lag of +0.04-0.08 rad. The bounds tell a kept aim from a lost
# one, off by up to pi for seconds: seen at load 8-20, where the robot's one executor
# delivered commands and states 0.1-4 s late and the Hi220 published frames read in a
# burst after a stall with fresh stamps on old orientation (IMU yaw 1.2 rad off at its
# stamp), which the odometry then kept as a yaw offset.
STATIC_AIM_TOLERANCE = 0.03  # [rad]
SPIN_AIM_P90 = 0.15  # [rad] 90 % of the samples while spinning
SPIN_AIM_MAX = 0.5  # [rad] the worst sample
# The point is level with the pivot: the barrel level, against the sim's 0.2 N*m of
# barrel gravity and the spin.
PITCH_TOLERANCE = 0.05  # [rad]


def aim_error(sample) -> float:
    """Barrel heading minus the bearing of the target from the robot [rad], wrapped."""
    bearing = math.atan2(TRACK_TARGET[1] - sample.y, TRACK_TARGET[0] - sample.x)
    return math.remainder(sample.barrel_yaw - bearing, 2.0 * math.pi)


def p90(values):
    ordered = sorted(abs(v) for v in values)
    return ordered[int(0.9 * (len(ordered) - 1))]


# A starved simulator is not a fault of the plugins: when rm_sim lets its clock slip
# (``sim_overruns``: it skipped physics to catch up with real time), the wheels moved
# less than the chassis plugin and the odometry believe, and the odometry keeps the
# difference as a heading offset (0.09-0.15 rad measured standing after 20-32 overruns at
# load 3-5; the stop after GYRO moved 0.104 rad against its 0.1 after 28). A check that
# fails on such a run is reported as an expected failure saying so; on a run where the
# simulator kept real time it fails (2 overruns already left the spinning aim p90 at
# 0.14 of its 0.15 rad). The Hi220 stamps frames when the device took them since 34efcde:
# a backlog after a stall no longer looks fresh.
MAX_SIM_OVERRUNS = 0


def judged_on_an_undisturbed_run(check):
    """Run check(result); excuse its failure only on a run the simulator could not keep."""

    def test(replayed):
        result = replayed('gyro_track')
        try:
            check(result)
        except AssertionError:
            if result.sim_overruns > MAX_SIM_OVERRUNS:
                pytest.xfail(f'machine too loaded: the simulator slipped '
                             f'{result.sim_overruns} times ({result.summary()})')
            raise

    test.__name__, test.__doc__ = check.__name__, check.__doc__
    return test


@judged_on_an_undisturbed_run
def test_when_gyro_spins_expect_more_than_three_and_a_half_turns(result):
    info = f'{result.summary()} -> {result.output}'
    spinning = result.body_between(GYRO_START_S, GYRO_END_S)
    turns = (spinning[-1].yaw - spinning[0].yaw) / (2.0 * math.pi)
    rates = [s.wz for s in result.body_between(GYRO_START_S + SETTLE_S, GYRO_END_S)]
    print(f'gyro: {turns:.2f} turns, wz {min(rates):.2f}..{max(rates):.2f} rad/s')
    assert turns > MIN_TURNS, info
    # ... and stops again after it (RAW, zero velocity, for 1 s): over the last 0.5 s the
    # heading moves by less than 0.1 rad (spinning on, it would turn 3 rad). The wheel
    # loops ring a little after braking from the spin (+-0.3 rad/s for ~1 s measured).
    still = result.body_between(GYRO_END_S + 0.5, GYRO_STOP_END_S)
    print(f'after GYRO: heading moved {still[-1].yaw - still[0].yaw:+.3f} rad in 0.5 s')
    assert abs(still[-1].yaw - still[0].yaw) < 0.1, info


@judged_on_an_undisturbed_run
def test_when_standing_expect_the_barrel_on_the_point(result):
    info = f'{result.summary()} -> {result.output}'
    errors = [aim_error(s) for s in result.body_between(STATIC_FROM_S, GYRO_START_S)]
    print(f'standing: aim error p90 {p90(errors):.4f} rad, max {max(map(abs, errors)):.4f}')
    assert max(map(abs, errors)) < STATIC_AIM_TOLERANCE, info


@judged_on_an_undisturbed_run
def test_when_gyro_spins_expect_the_barrel_kept_on_the_point(result):
    info = f'{result.summary()} -> {result.output}'
    window = result.body_between(GYRO_START_S + SETTLE_S, GYRO_END_S)
    errors = [aim_error(s) for s in window]
    pitch = max(abs(s.gimbal_pitch) for s in window)
    states = [m.state for m in result.messages('/gimbal_state')]
    tracking = states.count(GimbalCmd.TRACK) / len(states)
    print(
        f'spinning: aim error p90 {p90(errors):.4f} rad, max {max(map(abs, errors)):.4f}, '
        f'mean {sum(errors) / len(errors):+.4f} over {len(errors)} samples; pitch max '
        f'{pitch:.4f} rad; TRACK in {tracking:.0%} of the states'
    )
    assert len(errors) > 100, info  # 3.5 s at 10 ms
    assert p90(errors) < SPIN_AIM_P90, info
    assert max(map(abs, errors)) < SPIN_AIM_MAX, info
    assert pitch < PITCH_TOLERANCE, info
    # The plugin tracked all along (PASSIVE blips allowed: the process stalls for 0.1 s).
    assert tracking > 0.9, info
