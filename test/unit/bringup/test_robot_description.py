"""robot_description: the URDF Foxglove draws, built from the wheels and the gimbal."""

import xml.etree.ElementTree as ET

import pytest
from rm_bringup.robot_description import GimbalPlace, WheelPlace, robot_description

WHEELS = [WheelPlace(f'wheel_{n}', x, y, 0.076)
          for n, x, y in (('fl', 0.2, 0.2), ('fr', 0.2, -0.2), ('rl', -0.2, 0.2),
                          ('rr', -0.2, -0.2))]
GIMBAL = GimbalPlace('yaw_link', 'pitch_link', 'muzzle', (0.0, 0.0, 0.3), 0.15)


def test_each_wheel_is_a_link_at_its_place_and_the_gimbal_chain_ends_at_the_muzzle():
    robot = ET.fromstring(robot_description('standard', WHEELS, GIMBAL))
    assert robot.get('name') == 'standard'
    links = {link.get('name') for link in robot.iter('link')}
    assert links == {'base_link', 'wheel_wheel_fl', 'wheel_wheel_fr', 'wheel_wheel_rl',
                     'wheel_wheel_rr', 'yaw_link', 'pitch_link', 'muzzle'}
    joints = {j.get('name'): j for j in robot.iter('joint')}
    fl = joints['wheel_wheel_fl_mount']
    assert fl.find('origin').get('xyz') == '0.2000 0.2000 0.0760'
    assert (joints['yaw'].find('parent').get('link'), joints['yaw'].get('type')) == (
        'base_link', 'continuous')
    assert joints['yaw'].find('origin').get('xyz') == '0.0000 0.0000 0.3000'
    assert joints['pitch'].find('limit') is not None  # URDF asks a revolute joint for one
    assert joints['muzzle'].find('origin').get('xyz') == '0.1500 0.0000 0.0000'
    # the chassis box spans the wheels
    box = robot.find("link[@name='base_link']/visual/geometry/box")
    assert box.get('size').split()[0] == '0.4000'


def test_without_a_gimbal_only_the_chassis_and_without_wheels_an_error():
    robot = ET.fromstring(robot_description('x', WHEELS[:2], None))
    assert 'yaw_link' not in {link.get('name') for link in robot.iter('link')}
    with pytest.raises(ValueError, match='needs the chassis wheels'):
        robot_description('x', [], GIMBAL)
