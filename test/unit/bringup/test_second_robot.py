"""bringup's check for another robot in the same ROS domain."""

from rm_bringup.bringup import duplicated


def test_names_held_twice_are_another_robots():
    names = ['can_bridge', 'rm_robot', 'rm_sim', 'can_bridge', 'rm_sim', 'probe']
    assert duplicated(names, ['can_bridge', 'rm_robot', 'rm_sim']) == ['can_bridge', 'rm_sim']


def test_our_nodes_alone_are_no_one_elses():
    assert duplicated(['can_bridge', 'rm_robot'], ['can_bridge', 'rm_robot']) == []
