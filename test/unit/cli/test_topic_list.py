"""topic list output (ros2's format: names, -t types, -c count, hidden topics)."""

import time

from rm_bringup.cli.topic_list import format_topics

GRAPH = [
    ('/rosout', ['rcl_interfaces/msg/Log']),
    ('/chassis_cmd', ['rm_msgs/msg/ChassisCmd']),
    ('/_hidden/x', ['std_msgs/msg/String']),
    ('/mixed', ['std_msgs/msg/String', 'std_msgs/msg/Int32']),
]


def fmt(**kwargs):
    options = {'show_types': False, 'count_only': False, 'include_hidden': False} | kwargs
    return format_topics(GRAPH, **options)


def test_names_are_sorted_and_hidden_topics_left_out():
    assert fmt() == ['/chassis_cmd', '/mixed', '/rosout']


def test_show_types_appends_every_type_in_brackets():
    assert fmt(show_types=True)[:2] == [
        '/chassis_cmd [rm_msgs/msg/ChassisCmd]',
        '/mixed [std_msgs/msg/String, std_msgs/msg/Int32]',
    ]


def test_count_and_hidden_topics():
    assert fmt(count_only=True) == ['3']
    assert fmt(include_hidden=True)[0] == '/_hidden/x'


def test_the_list_is_taken_once_discovery_has_settled():
    # The finding: at the default 0.5 s, topics discovered later were silently missed.
    from rm_bringup.cli.topic_list import settled

    start = time.monotonic()
    graph = [[('/a', ['T'])], [('/a', ['T']), ('/b', ['T'])]]

    def read():  # a second topic is discovered 0.3 s in
        return graph[1] if time.monotonic() - start > 0.3 else graph[0]

    assert [n for n, _ in settled(read, 0.0, quiet_s=0.5, longest_s=3.0)] == ['/a', '/b']
    assert [n for n, _ in settled(lambda: graph[0], 0.0, quiet_s=0.2, longest_s=3.0)] == ['/a']


def test_a_graph_of_only_our_own_topics_is_not_settled():
    # The finding: `bag play` into a live robot judged the graph after 1 s of nothing
    # discovered yet, and replayed the robot's own states beside it.
    from rm_bringup.cli.topic_list import settled

    start = time.monotonic()
    own = [('/parameter_events', ['T']), ('/rosout', ['T'])]

    def read():  # the robot's topics come 1.3 s in, after more than quiet_s of nothing
        return [*own, ('/odom', ['T'])] if time.monotonic() - start > 1.3 else own

    assert '/odom' in [n for n, _ in settled(read, 0.0, quiet_s=0.5, longest_s=4.0)]
    begun = time.monotonic()
    assert settled(lambda: own, 0.0, quiet_s=0.1, longest_s=0.5) == own  # nobody: the longest
    assert time.monotonic() - begun >= 0.5
