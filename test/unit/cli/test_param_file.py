"""rmcli param load's choice of a file's sections: what rcl takes, not only ros2's one key."""

import pytest
from rm_bringup.cli.errors import CliError
from rm_bringup.cli.param_file import node_parameters

ROBOT = {'rm_robot': {'ros__parameters': {'shooter': {'max_hz': 8.0}, 'rate': 200}}}


@pytest.mark.parametrize(
    ('document', 'expected'),
    [
        # the relative name, as rm_bringup/config/ writes it, and the absolute, as dump does
        (ROBOT, {'shooter.max_hz': 8.0, 'rate': 200}),
        ({'/rm_robot': {'ros__parameters': {'a.b': 1}}}, {'a.b': 1}),
        # in the order written: the wildcard, the node's own sections over it
        (
            {
                '/**': {'ros__parameters': {'use_sim_time': True, 'a': 1}},
                'rm_robot': {'ros__parameters': {'a': 2, 'b': 2}},
                '/rm_robot': {'ros__parameters': {'b': 3}},
                'can_bridge': {'ros__parameters': {'c': 4}},
            },
            {'use_sim_time': True, 'a': 2, 'b': 3},
        ),
        ({'/**': {'ros__parameters': {'use_sim_time': True}}}, {'use_sim_time': True}),
        # rcl applies the sections in the file's order: the last one of the node's wins
        (
            {
                '/rm_robot': {'ros__parameters': {'a': 3}},
                'rm_robot': {'ros__parameters': {'a': 2}},
                '/**': {'ros__parameters': {'a': 1, 'b': 1}},
            },
            {'a': 1, 'b': 1},
        ),
    ],
)
def test_the_nodes_sections_are_merged_as_rcl_merges_them(document, expected):
    assert node_parameters(document, '/rm_robot', 'f.yaml') == expected


@pytest.mark.parametrize(
    ('document', 'message'),
    [
        ({'can_bridge': {'ros__parameters': {}}}, 'f.yaml: no parameters for /rm_robot (keys '
         'rm_robot, /rm_robot or /**); the file has: can_bridge'),
        ({}, 'the file has: none'),
        ([1, 2], 'f.yaml: not a ROS parameter file (a mapping of node names)'),
        (None, 'not a ROS parameter file'),
        ({'rm_robot': {'shooter.max_hz': 8.0}}, "f.yaml: 'rm_robot' has no 'ros__parameters'"),
        ({'rm_robot': None}, "'rm_robot' has no 'ros__parameters' mapping"),
    ],
)
def test_a_file_without_the_nodes_parameters_is_one_clear_error(document, message):
    with pytest.raises(CliError) as caught:
        node_parameters(document, '/rm_robot', 'f.yaml')
    assert message in str(caught.value)


def test_a_namespaced_node_takes_its_full_name_with_or_without_the_slash():
    document = {'team/rm_robot': {'ros__parameters': {'a': 1}}, 'rm_robot': {
        'ros__parameters': {'a': 9}}}
    assert node_parameters(document, '/team/rm_robot', 'f.yaml') == {'a': 1}
