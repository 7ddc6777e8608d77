"""Replay of test/data/teleop: a teleop_twist_keyboard session on /cmd_vel, played as /vel_cmd.

The bag holds what an operator's session records: Twist on /cmd_vel (forward, a left
curve, forward, a turn in place) and the chassis mode. The harness plays it with
``/cmd_vel:=/vel_cmd`` as ``rmcli bag play --remap`` does, and the robot (chassis only,
standard.yaml on rm_sim, lockstep) must drive the path the commands describe: their
twist, held from one message to the next, integrated along the robot's heading. Measured
(the same on every run): off the commanded path by at most 4.0 cm and 0.064 rad (the
ramps' lag behind each key), 1.0 cm and 0.023 rad at the end.
"""

from __future__ import annotations

import math

import pytest

from replay.scenarios import TELEOP_KEYS

pytestmark = [pytest.mark.ros, pytest.mark.slow]

STEP_S = 0.001  # [s] integration step of the commanded path
PATH_TOLERANCE = (0.06, 0.08)  # [m, rad] anywhere along the way: the ramps lag the keys
END_TOLERANCE = (0.03, 0.05)  # [m, rad] at rest at the end


def commanded_path(result, until: float) -> list[tuple[float, float, float, float]]:
    """(t, x, y, yaw) of the commands' twist, each held until the next, integrated."""
    commands = [(s.t, s.msg.linear.x, s.msg.linear.y, s.msg.angular.z)
                for s in result.sent['/vel_cmd']]
    x = y = yaw = vx = vy = wz = 0.0
    path, i, t = [], 0, 0.0
    while t <= until:
        while i < len(commands) and commands[i][0] <= t:
            _, vx, vy, wz = commands[i]
            i += 1
        heading = yaw + 0.5 * wz * STEP_S
        c, s = math.cos(heading), math.sin(heading)
        x += (c * vx - s * vy) * STEP_S
        y += (s * vx + c * vy) * STEP_S
        yaw += wz * STEP_S
        path.append((t, x, y, yaw))
        t += STEP_S
    return path


def test_the_teleop_bag_arrives_on_vel_cmd_and_nothing_on_cmd_vel(replayed):
    result = replayed('teleop')
    assert '/cmd_vel' not in result.sent
    keys = {(round(s.msg.linear.x, 3), round(s.msg.angular.z, 3)) for s in result.sent['/vel_cmd']}
    assert keys == {twist for _, _, twist in TELEOP_KEYS}


def test_the_robot_drives_the_path_the_teleop_commands_describe(replayed):
    result = replayed('teleop')
    info = f'{result.summary()} -> {result.output}'
    path = commanded_path(result, result.body[-1].t)
    worst = (0.0, 0.0)
    for sample in result.body:
        _, x, y, yaw = path[min(len(path) - 1, round(sample.t / STEP_S))]
        off = (math.hypot(sample.x - x, sample.y - y), abs(sample.yaw - yaw))
        worst = (max(worst[0], off[0]), max(worst[1], off[1]))
    print(f'teleop: off the commanded path by at most {worst[0]:.3f} m, {worst[1]:.3f} rad')
    assert worst[0] < PATH_TOLERANCE[0] and worst[1] < PATH_TOLERANCE[1], info
    _, x, y, yaw = path[-1]
    end = result.body[-1]
    assert math.hypot(end.x - x, end.y - y) < END_TOLERANCE[0], info
    assert abs(end.yaw - yaw) < END_TOLERANCE[1], info
    # the turns happened: a quarter turn on u (1 rad/s for 1.5 s) and 1.5 rad on j
    assert end.yaw == pytest.approx(3.0, abs=END_TOLERANCE[1])
