"""param_files: ROS parameter files read as rcl reads them, without rcl."""

import pytest
from rm_base.bridge.sim_process import bridge_parameters
from rm_base.config.param_files import flatten, load_parameters, nest, parameters_for
from rm_base.errors import ConfigError


def test_later_files_override_key_by_key_and_nesting_becomes_dots(tmp_path):
    base, overlay = tmp_path / 'robot.yaml', tmp_path / 'robot_sim.yaml'
    base.write_text('can_bridge: {ros__parameters: {buses: {can0: {interface: socketcan}}, '
                    'publish_rate: 200.0}}\n')
    overlay.write_text("can_bridge: {ros__parameters: {sim: true, 'sim.body': {x: 1}, "
                       'buses: {can0: {interface: rm_sim}}}}\n')
    params = load_parameters([base, overlay])['can_bridge']
    assert params == {
        'buses.can0.interface': 'rm_sim', 'publish_rate': 200.0, 'sim': True, 'sim.body.x': 1,
    }


def test_a_dumps_absolute_section_wins_over_the_configs_relative_one_in_any_file_order(
        tmp_path):
    # as rcl merges them (measured with rclpy): one entry per section name, applied in the
    # order the names first appear, each updated by every later file
    config, dump, overlay = (tmp_path / f'{n}.yaml' for n in ('config', 'dump', 'overlay'))
    config.write_text('can_bridge: {ros__parameters: {a: 1, b: 1}}\n')
    dump.write_text("'/can_bridge': {ros__parameters: {a: 2}}\n")
    overlay.write_text('can_bridge: {ros__parameters: {a: 3, b: 3}}\n')
    assert parameters_for(load_parameters([config, dump, overlay]), 'can_bridge') == {
        'a': 2, 'b': 3}
    assert parameters_for(load_parameters([dump, overlay]), '/can_bridge') == {'a': 3, 'b': 3}
    assert parameters_for(load_parameters([config]), '/rm_robot') == {}
    # rm_sim builds its world from the same merge as the bridge's (a joint a dump adds)
    assert bridge_parameters([config, dump, overlay]) == {'a': 2, 'b': 3}


@pytest.mark.parametrize('flat', [
    {'publish_rate': 200.0, 'buses.can0.interface': 'rm_sim', 'buses.can1.bitrate': 1000000},
    # can_bridge's `sim` is a parameter and a group: its members stay dotted beside it
    {'sim': True, 'sim.timing': 'realtime', 'sim.body.mass': 15.0, 'sim.body.inertia': 0.5},
    {'a.b': 1, 'a.b.c': 2, 'a.b.d.e': 3, 'a.f': 4},
    {},
])
def test_nest_writes_what_flatten_reads_back(flat):
    tree = nest(flat)
    assert flatten(tree) == flat
    for key, value in tree.items():  # no dict where a parameter's value is
        assert key in flat or isinstance(value, dict)


def test_a_parameter_that_is_a_group_too_keeps_its_members_dotted():
    assert nest({'sim': True, 'sim.timing': 'realtime', 'sim.body.mass': 15.0}) == {
        'sim': True, 'sim.timing': 'realtime', 'sim.body': {'mass': 15.0}}


@pytest.mark.parametrize(
    ('text', 'message'),
    [('[1, 2]\n', 'not a ROS parameter file'), ('a: [\n', r'robot\.yaml: ')],
)
def test_a_file_that_is_not_a_parameter_file_is_one_clear_error(tmp_path, text, message):
    path = tmp_path / 'robot.yaml'
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_parameters([path])


def test_a_missing_file_names_itself(tmp_path):
    with pytest.raises(ConfigError, match=r'nope\.yaml'):
        load_parameters([tmp_path / 'nope.yaml'])
