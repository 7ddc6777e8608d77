"""The manual-control mapping file: the default loads, every bad value names its key."""

import copy

import pytest
import yaml
from rm_base.hardware.protocols.dbus import Key
from rm_plugins.manual.mapping import Drive, MappingError, load_mapping, parse_mapping

from rm_msgs.msg import ChassisCmd, ShootCmd


@pytest.fixture(scope='module')
def default_data():
    from importlib import resources
    return yaml.safe_load(resources.files('rm_plugins.manual').joinpath(
        'default_mapping.yaml').read_text())


def test_the_default_mapping_loads_as_documented():
    m = load_mapping()
    assert m.right_switch == 'switch_a' and m.left_switch == 'switch_b'
    assert m.modes == {'up': Drive.KEYBOARD, 'mid': Drive.REMOTE, 'down': Drive.PASSIVE}
    assert m.remote.chassis_mode == ChassisCmd.FOLLOW
    assert (m.remote.vx.channel, m.remote.vx.scale) == (3, 2.0)
    assert m.remote.shooter == {'up': ShootCmd.PUSH, 'mid': ShootCmd.READY,
                                'down': ShootCmd.PASSIVE}
    assert m.keyboard.chassis_keys == {int(Key.F): ChassisCmd.GYRO, int(Key.G): ChassisCmd.TWIST}
    gears = {int(Key.SHIFT): ChassisCmd.GEAR_FAST, int(Key.CTRL): ChassisCmd.GEAR_SLOW}
    assert m.keyboard.gears == gears
    assert (m.shot_speed, m.shot_hz) == (15.0, 10.0)


def test_a_mapping_file_of_ones_own_is_read(tmp_path, default_data):
    data = copy.deepcopy(default_data)
    data['modes']['up'] = 'passive'
    path = tmp_path / 'mine.yaml'
    path.write_text(yaml.safe_dump(data))
    assert load_mapping(path).modes['up'] is Drive.PASSIVE


def test_a_missing_file_is_a_clear_error(tmp_path):
    with pytest.raises(MappingError, match=r'nope\.yaml'):
        load_mapping(tmp_path / 'nope.yaml')


@pytest.mark.parametrize(
    ('path', 'value', 'message'),
    [
        (('right_switch',), 'switch_c', 'right_switch'),
        (('modes', 'up'), 'autonomous', 'modes.up'),
        (('remote', 'chassis_mode'), 'HOVER', 'remote.chassis_mode'),
        (('remote', 'vx', 'channel'), 4, 'remote.vx.channel'),
        (('remote', 'vy', 'scale'), float('nan'), 'remote.vy.scale'),
        (('remote', 'shooter', 'up'), 'BURST', 'remote.shooter.up'),
        (('keyboard', 'speed'), -1.0, 'keyboard.speed'),
        (('keyboard', 'gears'), {'SPACE': 'FAST'}, 'keyboard.gears'),
        (('keyboard', 'gears'), {'SHIFT': 1.5}, 'keyboard.gears.SHIFT must be one of'),
        (('keyboard', 'gears'), {'SHIFT': 'TURBO'}, 'keyboard.gears.SHIFT must be one of'),
        (('keyboard', 'chassis_keys'), {'F': 'FLY'}, 'keyboard.chassis_keys.F'),
        (('keyboard', 'friction_key'), 'r', 'keyboard.friction_key'),
        (('keyboard', 'fire'), 'middle', 'keyboard.fire'),
        (('shooter', 'hz'), 0, 'shooter.hz'),
        (('keyboard', 'extra'), 1, 'unknown key'),
    ],
)
def test_a_bad_value_is_refused_naming_its_key(default_data, path, value, message):
    data = copy.deepcopy(default_data)
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(MappingError, match=message):
        parse_mapping(data)


def test_a_missing_key_is_named(default_data):
    data = copy.deepcopy(default_data)
    del data['keyboard']['mouse_yaw']
    with pytest.raises(MappingError, match=r'keyboard\.mouse_yaw'):
        parse_mapping(data)


def test_a_binary_file_is_a_clear_error_naming_it(tmp_path):
    path = tmp_path / 'mapping.yaml'
    path.write_bytes(bytes(range(128, 256)))
    with pytest.raises(MappingError, match=r'mapping\.yaml is not a text file'):
        load_mapping(path)


def test_a_bad_key_in_ones_own_file_names_the_file(tmp_path, default_data):
    path = tmp_path / 'mapping.yaml'
    path.write_text(yaml.safe_dump({**default_data, 'right_switch': 'switch_q'}))
    with pytest.raises(MappingError, match=r'mapping\.yaml: right_switch must be'):
        load_mapping(path)
