"""Which topics `bag play` leaves out: those published live by another node."""

from pathlib import Path
from types import SimpleNamespace

import pytest
from rm_bringup.cli.bag_topics import not_live
from rm_bringup.cli.errors import CliError


class Graph:
    """A node's view of the graph: topic -> publishers (at once, already discovered)."""

    def __init__(self, published: dict[str, list[str]]) -> None:
        self.published = published  # topic -> its publishers' node names

    def get_topic_names_and_types(self):
        return [(t, ['T']) for t in (*self.published, '/rosout')]

    def get_publishers_info_by_topic(self, topic):
        return [SimpleNamespace(node_name=n) for n in self.published.get(topic, [])]


def connections(*topics):
    return [SimpleNamespace(topic=t) for t in topics]


def test_a_robots_own_states_are_not_replayed_beside_it(capsys):
    graph = Graph({'/chassis_state': ['rm_robot'], '/odom': ['rm_robot'],
                   '/chassis_cmd': ['_rmcli_topic_pub_4242']})  # a tool's, not the robot's
    kept = not_live(graph, connections('/chassis_cmd', '/chassis_state', '/odom'), {},
                    Path('run1'))
    assert [c.topic for c in kept] == ['/chassis_cmd']
    assert 'not playing /chassis_state, /odom: published live' in capsys.readouterr().err


def test_when_everything_is_live_expect_an_error_naming_the_way_out():
    # judged by the name a topic is played under: /cmd_vel played as the live /vel_cmd
    graph = Graph({'/vel_cmd': ['planner']})
    with pytest.raises(CliError, match='name the ones to play in --topics'):
        not_live(graph, connections('/cmd_vel'), {'/cmd_vel': '/vel_cmd'}, Path('teleop'))
