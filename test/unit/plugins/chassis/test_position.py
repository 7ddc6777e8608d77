"""POSITION's law: goals from the pose at the start, a speed that can brake in time, arrival."""

import math

import pytest
from rm_plugins.chassis.position import (
    DEFAULT_POSITION,
    Goal,
    approach_speed,
    goal_of,
    position_command,
)


def test_the_goal_is_the_move_along_the_robots_axes_at_the_start():
    goal = goal_of(1.0, 2.0, math.pi / 2, (1.0, 0.5, math.pi))
    assert (goal.x, goal.y, goal.yaw) == pytest.approx((0.5, 3.0, -math.pi / 2))


@pytest.mark.parametrize(
    ('distance', 'brake', 'speed'),
    [
        (10.0, 4.0, 1.5),  # far: the top speed
        (0.5, 0.5, math.sqrt(2 * 0.5 * 0.5)),  # braking distance: sqrt(2 a d)
        (0.01, 4.0, 0.04),  # near: the gain
        (0.2, None, 0.8),  # unlimited braking: the gain alone
        (0.0, 4.0, 0.0),
    ],
)
def test_the_approach_speed_is_the_least_of_top_braking_and_gain(distance, brake, speed):
    assert approach_speed(distance, 1.5, brake, 4.0) == pytest.approx(speed)


def test_the_command_points_at_the_goal_and_says_when_it_has_arrived():
    goal = Goal(3.0, 4.0, 1.0)
    (vx, vy, wz), arrived = position_command((0.0, 0.0, 0.0), goal, DEFAULT_POSITION, (8, 40))
    assert (vx, vy) == pytest.approx((0.9, 1.2))  # 1.5 m/s toward (3, 4)
    assert wz == pytest.approx(3.0) and not arrived
    near = (3.0 - 0.01, 4.0, 1.0 + 0.015)
    (vx, vy, wz), arrived = position_command(near, goal, DEFAULT_POSITION, (8, 40))
    assert arrived and vx == pytest.approx(0.04) and wz == pytest.approx(-0.06)
    (_, _, wz), _ = position_command((3.0, 4.0, 3.0), Goal(3.0, 4.0, -3.0), DEFAULT_POSITION,
                                     (8, 40))
    assert wz > 0.0  # the short way round, through pi
