"""Robot body: chassis pose from wheel speeds, gimbal joints, body orientation."""

import math

import numpy as np
import pytest
from rm_base.geometry import WheelKinematics, mecanum_wheels, rotation_matrix_from_rpy
from rm_base.sim import Mount, SimConfigError

from .helpers import unique_channel

R = 0.076  # wheel radius [m]
LX, LY = 0.2, 0.15  # half wheelbase, half track [m]
FREE = {'coulomb_friction': 0.0, 'viscous_friction': 0.0}
WHEELS = ['wheel_fl', 'wheel_fr', 'wheel_rl', 'wheel_rr']


def robot_config(directions=(1, 1, 1, 1), gimbal=None, pose=(0.0, 0.0, 0.0)):
    motors = [{'type': 'm3508', 'id': i + 1, 'name': n, **FREE} for i, n in enumerate(WHEELS)]
    motors += [
        {'type': 'gm6020', 'id': 1, 'name': 'yaw', **FREE},
        {'type': 'gm6020', 'id': 2, 'name': 'pitch', **FREE},
    ]
    body = {
        'initial_pose': list(pose),
        'chassis': {
            'type': 'mecanum',
            'motors': WHEELS,
            'wheelbase': 2 * LX,
            'track': 2 * LY,
            'wheel_radius': R,
            'directions': list(directions),
        },
        'gimbal': gimbal or {'yaw': {'motor': 'yaw'}, 'pitch': {'motor': 'pitch'}},
    }
    return {'channels': {unique_channel(): motors}, 'body': body}


def spin_wheels(world, twist, directions=(1, 1, 1, 1)):
    """Set each (frictionless, unpowered) wheel motor to the speed giving twist."""
    kinematics = WheelKinematics(mecanum_wheels(2 * LX, 2 * LY, R))
    for name, speed, d in zip(WHEELS, kinematics.inverse(twist), directions, strict=True):
        world.motor(name).model.reset(velocity=d * speed)


def test_when_wheels_roll_forward_expect_chassis_moves_r_omega_t(make_world):
    # All four wheels at 10 rad/s: vx = r*w = 0.76 m/s; after 1 s, x = 0.76 m.
    world = make_world(robot_config())
    for name in WHEELS:
        world.motor(name).model.reset(velocity=10.0)
    world.step(1000)
    body = world.body
    assert body.x == pytest.approx(0.76, rel=1e-9)
    assert body.y == pytest.approx(0.0, abs=1e-12)
    assert body.yaw == pytest.approx(0.0, abs=1e-12)
    assert body.twist == pytest.approx((0.76, 0.0, 0.0))


def test_when_wheel_directions_flip_expect_same_motion(make_world):
    # Right-side motors mounted mirrored: motor speed = -wheel speed.
    directions = (1, -1, 1, -1)
    world = make_world(robot_config(directions=directions))
    spin_wheels(world, (0.0, 0.5, 0.0), directions)
    world.step(1000)
    assert world.body.y == pytest.approx(0.5, rel=1e-9)
    assert world.body.x == pytest.approx(0.0, abs=1e-12)


def test_when_wheels_spin_in_place_expect_yaw_integrates(make_world):
    world = make_world(robot_config())
    spin_wheels(world, (0.0, 0.0, 1.0))
    world.step(2000)
    assert world.body.yaw == pytest.approx(2.0, rel=1e-9)
    assert math.hypot(world.body.x, world.body.y) < 1e-9


def test_when_heading_is_left_expect_forward_motion_along_world_y(make_world):
    world = make_world(robot_config(pose=(1.0, 2.0, math.pi / 2)))
    spin_wheels(world, (0.4, 0.0, 0.0))
    world.step(500)
    assert (world.body.x, world.body.y) == pytest.approx((1.0, 2.2))


def test_when_driving_an_arc_expect_the_circle(make_world):
    # vx = 0.5 m/s, wz = 0.5 rad/s: a circle of radius 1 m; after pi s, half of it:
    # from (0, 0) heading +x to (0, 2) heading -x. The midpoint rule keeps it to ~1e-7.
    world = make_world(robot_config())
    spin_wheels(world, (0.5, 0.0, 0.5))
    world.advance(math.pi)
    ticks = round(math.pi * 1000)
    yaw = 0.5 * ticks / 1000
    expected = (math.sin(yaw), 1.0 - math.cos(yaw))
    assert (world.body.x, world.body.y) == pytest.approx(expected, abs=1e-6)


def test_when_chassis_spins_under_a_free_gimbal_expect_gimbal_keeps_its_heading(make_world):
    # The yaw load keeps its inertia in the world: an unpowered, frictionless gimbal stays
    # pointed while the chassis turns under it (the encoder sees -chassis yaw).
    world = make_world(robot_config())
    spin_wheels(world, (0.0, 0.0, 2.0))
    world.step(500)
    body = world.body
    assert body.yaw == pytest.approx(1.0, rel=1e-9)
    assert body.gimbal_yaw == pytest.approx(-1.0, rel=1e-6)
    assert body.yaw + body.gimbal_yaw == pytest.approx(0.0, abs=1e-6)


def test_when_yaw_inertia_in_chassis_frame_expect_gimbal_turns_with_chassis(make_world):
    gimbal = {'yaw': {'motor': 'yaw', 'world_frame_inertia': False}}
    world = make_world(robot_config(gimbal=gimbal))
    spin_wheels(world, (0.0, 0.0, 2.0))
    world.step(500)
    assert world.body.gimbal_yaw == 0.0


def test_gimbal_joint_angles_use_direction_and_zero(make_world):
    gimbal = {
        'yaw': {'motor': 'yaw', 'direction': -1, 'zero': 0.5},
        'pitch': {'motor': 'pitch', 'zero': -0.1},
    }
    world = make_world(robot_config(gimbal=gimbal))
    world.motor('yaw').model.reset(angle=0.8)
    world.motor('pitch').model.reset(angle=0.2)
    assert world.body.gimbal_yaw == pytest.approx(-0.3)
    assert world.body.gimbal_pitch == pytest.approx(0.3)


def test_gimbal_orientation_is_yaw_then_pitch(make_world):
    world = make_world(robot_config(pose=(0.0, 0.0, 0.4)))
    world.motor('yaw').model.reset(angle=0.3)
    world.motor('pitch').model.reset(angle=-0.2)
    body = world.body
    expected = rotation_matrix_from_rpy(0.0, -0.2, 0.7)
    np.testing.assert_allclose(body.orientation(Mount.GIMBAL), expected, atol=1e-12)
    np.testing.assert_allclose(
        body.orientation(Mount.CHASSIS), rotation_matrix_from_rpy(0.0, 0.0, 0.4), atol=1e-12
    )


def test_gimbal_angular_velocity_adds_yaw_and_pitch_rates(make_world):
    # Chassis wz = 1, yaw joint +0.5 rad/s, pitch joint 2 rad/s about the gimbal's y axis,
    # which is world y turned by the gimbal heading.
    world = make_world(
        robot_config(
            gimbal={
                'yaw': {'motor': 'yaw', 'world_frame_inertia': False},
                'pitch': {'motor': 'pitch'},
            }
        )
    )
    spin_wheels(world, (0.0, 0.0, 1.0))
    world.motor('yaw').model.reset(velocity=0.5)
    world.motor('pitch').model.reset(velocity=2.0)
    body = world.body
    body.update_chassis(1e-3)  # takes up the wheel speeds (and turns by 1 mrad)
    heading = body.yaw + body.gimbal_yaw
    omega = body.angular_velocity(Mount.GIMBAL)
    expected = [-2.0 * math.sin(heading), 2.0 * math.cos(heading), 1.5]
    np.testing.assert_allclose(omega, expected, atol=1e-9)


def test_when_pitch_carries_gravity_torque_expect_it_noses_down(make_world):
    # 0.3 N·m at 0 pitch on a frictionless GM6020 (2e-4 kg·m²): after 10 ms,
    # w = tau/J * t = 1500 * 0.01 = 15 rad/s (cos(pitch) stays ~1 over 75 mrad).
    gimbal = {'pitch': {'motor': 'pitch', 'direction': -1, 'gravity_torque': 0.3}}
    world = make_world(robot_config(gimbal=gimbal))
    world.step(10)
    assert world.body.gimbal_pitch > 0.0
    assert world.motor('pitch').model.velocity == pytest.approx(-15.0, rel=0.01)


@pytest.mark.parametrize('direction', [1, -1])
def test_a_limp_barrel_rests_on_its_end_stop(make_world, direction):
    # The finding: a limp barrel fell to 1.47 rad, far past pitch_max 0.30.
    gimbal = {'pitch': {'motor': 'pitch', 'direction': direction, 'gravity_torque': 0.3,
                        'end_stops': [-0.5, 0.35]}}
    world = make_world(robot_config(gimbal=gimbal))
    world.step(2000)
    assert world.body.gimbal_pitch == pytest.approx(0.35, abs=1e-9)
    assert world.body.pitch_joint.velocity == 0.0
    world.motor('pitch').model.external_torque = 0.0
    world.body.pitch_gravity_torque = -0.3  # now tail-heavy: off the stop, to the other
    world.step(2000)
    assert world.body.gimbal_pitch == pytest.approx(-0.5, abs=1e-9)


@pytest.mark.parametrize(
    ('change', 'message'),
    [
        ({'gimbal': {'pitch': {'motor': 'pitch', 'end_stops': [0.3, -0.3]}}},
         r'body\.gimbal\.pitch\.end_stops must be \[low, high\], low < high'),
        ({'chassis': {'type': 'tank'}},
         r"body\.chassis\.type must be one of mecanum, omni, swerve, wheels, got 'tank'"),
        ({'chassis': {'type': 'mecanum'}}, r'body\.chassis\.motors is required'),
        ({'gimbal': {'yaw': {'motor': 'nope'}}},
         r"body\.gimbal\.yaw\.motor is 'nope', which is not a configured motor"),
        ({'gimbal': {'roll': {'motor': 'yaw'}}}, r"body\.gimbal: unknown key\(s\) \['roll'\]"),
        ({'gimbal': {'yaw': {'motor': 'yaw', 'direction': 2}}},
         r'body\.gimbal\.yaw\.direction must be one of 1, -1, got 2'),
        ({'gimbal': {'pitch': {'motor': 'pitch', 'gravity_torque': 'lots'}}},
         r"body\.gimbal\.pitch\.gravity_torque must be double \[N·m\]; got str 'lots'"),
        ({'gimbal': {'yaw': {'motor': 'yaw', 'world_frame_inertia': 1}}},
         r'body\.gimbal\.yaw\.world_frame_inertia must be bool'),
        ({'initial_pose': [0, 0]}, r'body\.initial_pose must have 3 entries, has 2'),
        ({'initial_pose': [0, 0, float('nan')]}, r'body\.initial_pose entry \[2\] must be finite'),
        ({'gravity': 9.8}, r"body: unknown key\(s\) \['gravity'\]"),
    ],
)
def test_when_bad_body_config_expect_config_error(make_world, change, message):
    config = robot_config()
    config['body'] = {**config['body'], **change}
    with pytest.raises(SimConfigError, match=message):
        make_world(config)


def test_when_chassis_names_too_few_motors_expect_config_error(make_world):
    config = robot_config()
    config['body']['chassis']['motors'] = WHEELS[:3]
    with pytest.raises(SimConfigError, match='must name 4 motors'):
        make_world(config)


@pytest.mark.parametrize(
    ('chassis', 'message'),
    [
        ({'directions': [1, -1, 1]}, r'body\.chassis\.directions must have one entry per wheel'),
        ({'directions': [1, -1, 1, 0]},
         r'body\.chassis\.directions entry \[3\] must be 1 or -1, got 0'),
        ({'wheelbase': -0.4}, r'body\.chassis\.wheelbase must be > 0\.0, got -0\.4'),
        ({'type': 'wheels', 'wheels': [{'motor': 'wheel_fl', 'x': 0.0, 'y': 0.2}]},
         r'body\.chassis: unknown key\(s\)'),
    ],
)
def test_when_bad_chassis_expect_the_key_named(make_world, chassis, message):
    config = robot_config()
    config['body']['chassis'] = {**config['body']['chassis'], **chassis}
    with pytest.raises(SimConfigError, match=message):
        make_world(config)


def test_when_a_listed_wheel_is_bad_expect_its_index_named(make_world):
    config = robot_config()
    wheel = {'motor': 'wheel_fl', 'x': 0.0, 'y': 0.2, 'radius': 0.05}
    config['body']['chassis'] = {'type': 'wheels', 'wheels': [wheel, {**wheel, 'radius': 0}]}
    with pytest.raises(SimConfigError, match=r'body\.chassis\.wheels\[1\]\.radius must be > 0'):
        make_world(config)


def test_omni_and_explicit_wheel_chassis(make_world):
    # Three omni wheels at 90°, 210°, 330°, 0.2 m out, rolling tangentially: equal wheel
    # speeds w turn the chassis at wz = r*w / 0.2 = 0.05*4/0.2 = 1 rad/s.
    config = robot_config()
    omni = {
        'type': 'omni',
        'motors': WHEELS[:3],
        'mounting_angles': [math.pi / 2, 7 * math.pi / 6, 11 * math.pi / 6],
        'centre_distance': 0.2,
        'wheel_radius': 0.05,
    }
    config['body'] = {'chassis': omni}
    world = make_world(config)
    for name in WHEELS[:3]:
        world.motor(name).model.reset(velocity=4.0)
    world.step(100)
    assert world.body.yaw == pytest.approx(0.1, rel=1e-9)


def test_explicit_wheel_list_chassis(make_world):
    # Three omni wheels given one by one, all rolling +x except one rolling +y at the
    # front: wheel i speed = (n_i . v) / r. Driving vx = 0.1 needs 2 rad/s on the
    # x-rolling wheels and 0 on the other.
    config = robot_config()
    wheels = [
        {'motor': 'wheel_fl', 'x': 0.0, 'y': 0.2, 'radius': 0.05},
        {'motor': 'wheel_fr', 'x': 0.0, 'y': -0.2, 'radius': 0.05, 'direction': -1},
        {'motor': 'wheel_rl', 'x': 0.2, 'y': 0.0, 'radius': 0.05, 'rolling_direction': math.pi / 2},
    ]
    config['body'] = {'chassis': {'type': 'wheels', 'wheels': wheels}}
    world = make_world(config)
    world.motor('wheel_fl').model.reset(velocity=2.0)
    world.motor('wheel_fr').model.reset(velocity=-2.0)
    world.step(1000)
    assert (world.body.x, world.body.y, world.body.yaw) == pytest.approx((0.1, 0.0, 0.0))


STEERS = ['steer_fl', 'steer_fr', 'steer_rl', 'steer_rr']


def swerve_config(**chassis):
    motors = [{'type': 'm3508', 'id': i + 1, 'name': n, **FREE} for i, n in enumerate(WHEELS)]
    motors += [
        {'type': 'gm6020', 'id': i + 1, 'name': n, **FREE} for i, n in enumerate(STEERS)
    ]
    body = {
        'chassis': {
            'type': 'swerve', 'motors': WHEELS, 'steer_motors': STEERS,
            'wheelbase': 2 * LX, 'track': 2 * LY, 'wheel_radius': R, **chassis,
        },
    }
    return {'channels': {unique_channel(): motors}, 'body': body}


def test_a_swerve_chassis_drives_where_its_modules_point(make_world):
    # every module at 90° (left), its wheel at 10 rad/s: vy = r*w = 0.76 m/s, no turn
    world = make_world(swerve_config())
    for steer, wheel in zip(STEERS, WHEELS, strict=True):
        world.motor(steer).model.reset(angle=math.pi / 2)
        world.motor(wheel).model.reset(velocity=10.0)
    world.step(1000)
    body = world.body
    assert (body.x, body.y, body.yaw) == pytest.approx((0.0, 0.76, 0.0), abs=1e-9)


def test_a_swerve_chassis_turns_in_place_with_its_modules_tangential(make_world):
    # modules at 45° off the diagonal (tangential), wheels at w: wz = r*w / hypot(lx, ly)
    steer_zeros = [0.3, -0.2, 0.0, 0.1]  # where each steering motor reads 0
    world = make_world(swerve_config(steer_zeros=steer_zeros, steer_directions=[1, 1, -1, 1]))
    for i, (x, y) in enumerate(((LX, LY), (LX, -LY), (-LX, LY), (-LX, -LY))):
        tangent = math.atan2(x, -y)  # direction of the hub's motion when turning +z
        direction = -1 if i == 2 else 1
        world.motor(STEERS[i]).model.reset(angle=direction * tangent + steer_zeros[i])
        world.motor(WHEELS[i]).model.reset(velocity=4.0)
    world.step(100)
    wz = R * 4.0 / math.hypot(LX, LY)
    assert world.body.twist == pytest.approx((0.0, 0.0, wz), abs=1e-9)
    assert world.body.yaw == pytest.approx(0.1 * wz, rel=1e-9)


@pytest.mark.parametrize(
    ('chassis', 'message'),
    [
        ({'steer_motors': STEERS[:3]}, r'body\.chassis\.steer_motors must name 4 motors'),
        ({'steer_motors': [*STEERS[:3], 'nope']},
         r"body\.chassis\.steer_motors is 'nope', which is not a configured motor"),
        ({'steer_zeros': [0.0, 0.0]},
         r'body\.chassis\.steer_zeros must have one entry per module \(4\), has 2'),
        ({'steer_directions': [1, 1, 1, 2]},
         r'body\.chassis\.steer_directions entry \[3\] must be 1 or -1, got 2'),
        ({'steer_motors': None}, r'body\.chassis\.steer_motors is required'),
    ],
)
def test_when_a_swerve_chassis_is_bad_expect_the_key_named(make_world, chassis, message):
    config = swerve_config()
    table = {**config['body']['chassis'], **chassis}
    config['body']['chassis'] = {k: v for k, v in table.items() if v is not None}
    with pytest.raises(SimConfigError, match=message):
        make_world(config)


def test_a_chassis_checks_its_wheels_against_its_kinematics(make_world):
    from rm_base.geometry import SwerveKinematics, square_modules
    from rm_base.sim.body import Chassis
    from rm_base.sim.joint import Joint

    world = make_world(swerve_config())
    wheels = [world.motor(n) for n in WHEELS]
    steering = [Joint(world.motor(n)) for n in STEERS]
    fixed = WheelKinematics(mecanum_wheels(2 * LX, 2 * LY, R))
    swerve = SwerveKinematics(square_modules(2 * LX, 2 * LY, R))
    with pytest.raises(SimConfigError, match='fixed wheels have no steering joints'):
        Chassis(fixed, wheels, steering=steering)
    with pytest.raises(SimConfigError, match=r'one steering joint per module \(4\), got 3'):
        Chassis(swerve, wheels, steering=steering[:3])
    with pytest.raises(SimConfigError, match='4 wheels in the kinematics, 3 motors'):
        Chassis(fixed, wheels[:3])
    assert Chassis(swerve, wheels, steering=steering).motors == (
        *wheels, *(j.device for j in steering)
    )
