import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from rm_base.errors import ConfigError, InputRejectedError
from rm_base.geometry import (
    SE2,
    SE3,
    GimbalMount,
    ProjectileModel,
    aim_at,
    aim_from_point,
    pitch_axis_in_world,
    rotation_matrix_from_rpy,
    solve_ballistic,
    trajectory_height,
)


def barrel_direction(yaw, pitch):
    """World direction of the barrel: Rz(yaw) @ Ry(pitch) @ x (REP 103)."""
    return rotation_matrix_from_rpy(0.0, pitch, yaw) @ np.array([1.0, 0.0, 0.0])


def test_when_target_straight_ahead_level_expect_zero_yaw_and_pitch():
    aim = aim_from_point((0.0, 0.0, 0.4), (5.0, 0.0, 0.4))
    assert aim == (0.0, 0.0, 5.0, None)


def test_when_target_left_and_above_expect_positive_yaw_negative_pitch():
    aim = aim_from_point((0.0, 0.0, 0.0), (3.0, 3.0, 1.0))
    # yaw = atan2(3, 3) = pi/4 (left is counter-clockwise, positive);
    # horizontal distance 3 sqrt(2) = 4.242641; elevation atan2(1, 4.242641) = 0.231477,
    # and above the horizon is a negative REP 103 pitch: -0.231477.
    assert aim.yaw == pytest.approx(math.pi / 4)
    assert aim.distance == pytest.approx(4.242641, rel=1e-6)
    assert aim.pitch == pytest.approx(-0.231477, rel=1e-5)
    assert barrel_direction(aim.yaw, aim.pitch)[2] > 0.0  # the barrel does point up


def test_when_target_behind_expect_yaw_pi():
    assert aim_from_point((0.0, 0.0, 0.0), (-2.0, 0.0, 0.0)).yaw == pytest.approx(math.pi)


def test_when_chassis_moved_and_turned_expect_mount_offset_in_world():
    # Chassis at (1, 2) heading pi/2 (facing +y); the pitch axis centre 0.1 m ahead of the
    # base origin and 0.3 m up: ahead is world +y, so (1, 2 + 0.1, 0.3).
    centre = pitch_axis_in_world(
        SE2.from_xy_yaw(1.0, 2.0, math.pi / 2), GimbalMount((0.1, 0.0, 0.3))
    )
    assert centre == pytest.approx([1.0, 2.1, 0.3])


def test_when_chassis_tilted_expect_pitch_axis_centre_tilted_with_it():
    # Chassis nosed down 0.1 rad (positive REP 103 pitch) on a slope; a centre 0.5 m above
    # the base moves forward: R_y(0.1) (0, 0, 0.5) = (0.5 sin 0.1, 0, 0.5 cos 0.1)
    # = (0.049917, 0, 0.497502).
    pose = SE3.from_translation_rpy((0.0, 0.0, 0.0), 0.0, 0.1, 0.0)
    centre = pitch_axis_in_world(pose, GimbalMount((0.0, 0.0, 0.5)))
    assert centre == pytest.approx([0.049917, 0.0, 0.497502], abs=1e-6)


def test_when_aiming_from_chassis_expect_aim_from_pitch_axis_centre():
    pose = SE2.from_xy_yaw(1.0, 2.0, math.pi / 2)
    # Centre at (1, 2.1, 0.3) as above; a target 3 m further along +y at the same height:
    # yaw pi/2, level, 3 m.
    aim = aim_at((1.0, 5.1, 0.3), pose, GimbalMount((0.1, 0.0, 0.3)))
    assert aim.yaw == pytest.approx(math.pi / 2)
    assert aim.pitch == pytest.approx(0.0, abs=1e-12)
    assert aim.distance == pytest.approx(3.0)


@pytest.mark.parametrize('chassis_yaw', [0.0, 1.0, 2.5, -2.0])
def test_when_chassis_spins_under_centred_gimbal_expect_same_world_aim(chassis_yaw):
    # The pitch axis centre on the yaw axis (offset x = y = 0): spinning the chassis (GYRO)
    # must not move the world aim at all.
    pose = SE2.from_xy_yaw(0.5, -0.5, chassis_yaw)
    aim = aim_at((4.0, 1.0, 0.2), pose, GimbalMount((0.0, 0.0, 0.35)), bullet_speed=25.0)
    reference = aim_at(
        (4.0, 1.0, 0.2),
        SE2.from_xy_yaw(0.5, -0.5, 0.0),
        GimbalMount((0.0, 0.0, 0.35)),
        bullet_speed=25.0,
    )
    assert aim == pytest.approx(reference, abs=1e-12)


def test_when_bullet_speed_given_expect_ballistic_pitch():
    model = ProjectileModel(drag=0.02)
    aim = aim_from_point((0.0, 0.0, 0.0), (6.0, 8.0, 0.5), bullet_speed=25.0, model=model)
    # Horizontal distance hypot(6, 8) = 10 m, 0.5 m up: the ballistic solution for that.
    expected = solve_ballistic(10.0, 0.5, 25.0, model)
    assert aim.yaw == pytest.approx(math.atan2(8.0, 6.0))
    assert aim.pitch == pytest.approx(expected.pitch)
    assert aim.time_of_flight_s == pytest.approx(expected.time_of_flight_s)
    assert aim.pitch < -math.atan2(0.5, 10.0)  # aimed above the line of sight


def test_when_barrel_length_given_expect_shot_from_muzzle_hits():
    model = ProjectileModel(drag=0.02)
    length = 0.25
    aim = aim_from_point(
        (0.0, 0.0, 0.0), (3.0, 0.0, 0.8), bullet_speed=15.0, model=model, barrel_length=length
    )
    elevation = -aim.pitch
    # The muzzle is 0.25 m along the barrel: (0.25 cos e, 0.25 sin e); from there the
    # target is 3 - 0.25 cos e ahead and 0.8 - 0.25 sin e up.
    height, time_s = trajectory_height(3.0 - length * math.cos(elevation), aim.pitch, 15.0, model)
    assert height == pytest.approx(0.8 - length * math.sin(elevation), abs=1e-6)
    assert time_s == pytest.approx(aim.time_of_flight_s)
    # Ignoring the barrel would aim differently (the muzzle is nearer and higher).
    assert aim.pitch != pytest.approx(
        aim_from_point((0.0, 0.0, 0.0), (3.0, 0.0, 0.8), bullet_speed=15.0, model=model).pitch,
        abs=1e-4,
    )


def test_when_target_out_of_range_expect_none():
    # Level vacuum range at 10 m/s is v² / g = 10.2 m.
    assert aim_from_point((0.0, 0.0, 0.0), (20.0, 0.0, 0.0), bullet_speed=10.0) is None


def test_when_target_straight_above_expect_none():
    assert aim_from_point((1.0, 1.0, 0.0), (1.0, 1.0, 2.0)) is None


def test_when_target_within_barrel_reach_expect_none():
    assert (
        aim_from_point((0.0, 0.0, 0.0), (0.1, 0.0, 0.0), bullet_speed=20.0, barrel_length=0.3)
        is None
    )


@pytest.mark.parametrize(
    ('kwargs', 'message'),
    [
        ({'target': (1.0, math.nan, 0.0)}, 'target'),
        ({'target': (1.0, 0.0)}, 'target'),
        ({'origin': (math.inf, 0.0, 0.0)}, 'origin'),
        ({'bullet_speed': 0.0}, 'bullet speed'),
        ({'bullet_speed': math.nan}, 'bullet speed'),
        ({'bullet_speed': 20.0, 'barrel_length': -0.1}, 'barrel_length'),
    ],
)
def test_when_input_invalid_expect_rejected(kwargs, message):
    args = {'origin': (0.0, 0.0, 0.0), 'target': (5.0, 0.0, 0.0), **kwargs}
    origin, target = args.pop('origin'), args.pop('target')
    with pytest.raises(InputRejectedError, match=message):
        aim_from_point(origin, target, **args)


def test_when_base_pose_not_a_transform_expect_rejected():
    with pytest.raises(InputRejectedError, match='base_pose'):
        aim_at((1.0, 0.0, 0.0), (0.0, 0.0, 0.0), GimbalMount())


@pytest.mark.parametrize(
    ('kwargs', 'message'),
    [
        ({'pitch_axis_offset': (0.0, 0.0)}, 'pitch_axis_offset'),
        ({'pitch_axis_offset': (0.0, math.nan, 0.0)}, 'pitch_axis_offset'),
        ({'pitch_axis_offset': None}, 'pitch_axis_offset'),
        ({'barrel_length': -0.1}, 'barrel_length'),
        ({'barrel_length': math.inf}, 'barrel_length'),
    ],
)
def test_when_mount_invalid_expect_config_error(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        GimbalMount(**kwargs)


coordinate = st.floats(min_value=-10.0, max_value=10.0)
angle = st.floats(min_value=-math.pi, max_value=math.pi)
tilt = st.floats(min_value=-0.3, max_value=0.3)
offset = st.floats(min_value=-0.3, max_value=0.5)


@given(
    st.tuples(coordinate, coordinate, st.floats(min_value=0.0, max_value=1.0)),
    st.tuples(tilt, tilt, angle),
    st.tuples(offset, offset, offset),
    st.tuples(coordinate, coordinate, st.floats(min_value=-1.0, max_value=3.0)),
)
def test_invariant_aim_points_at_target(position, rpy, mount_offset, target):
    pose = SE3.from_translation_rpy(position, *rpy)
    mount = GimbalMount(mount_offset)
    centre = pitch_axis_in_world(pose, mount)
    to_target = np.asarray(target) - centre
    assume(math.hypot(to_target[0], to_target[1]) > 1e-3)
    aim = aim_at(target, pose, mount)
    direction = barrel_direction(aim.yaw, aim.pitch)
    # Parallel and the same way: unit direction times the range is the offset.
    assert direction * np.linalg.norm(to_target) == pytest.approx(to_target, abs=1e-9)


@given(
    st.tuples(coordinate, coordinate, st.floats(min_value=-1.0, max_value=3.0)),
    st.floats(min_value=12.0, max_value=30.0),
    st.sampled_from([0.0, 0.02]),
    st.floats(min_value=0.0, max_value=0.3),
)
def test_invariant_ballistic_aim_from_muzzle_hits_target(target, speed, drag, length):
    assume(math.hypot(target[0], target[1]) > 0.05)  # not straight up: pitch near -pi/2
    model = ProjectileModel(drag=drag)
    aim = aim_from_point(
        (0.0, 0.0, 0.0), target, bullet_speed=speed, model=model, barrel_length=length
    )
    assume(aim is not None)
    elevation = -aim.pitch
    muzzle = length * np.array(
        [
            math.cos(elevation) * math.cos(aim.yaw),
            math.cos(elevation) * math.sin(aim.yaw),
            math.sin(elevation),
        ]
    )
    to_target = np.asarray(target) - muzzle
    # Same vertical plane: from the muzzle the target is still straight along the yaw
    # (no sideways component, and ahead rather than behind).
    heading = np.array([math.cos(aim.yaw), math.sin(aim.yaw)])
    assert heading[0] * to_target[1] - heading[1] * to_target[0] == pytest.approx(0.0, abs=1e-9)
    assert heading @ to_target[:2] > 0.0
    reached, _ = trajectory_height(math.hypot(to_target[0], to_target[1]), aim.pitch, speed, model)
    assert reached == pytest.approx(to_target[2], abs=1e-6)
