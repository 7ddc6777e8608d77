"""bag record's topic selection (rosbag2's rules)."""

import re

import pytest
from rm_bringup.cli.bag_record import TopicSelection, selection_from_args
from rm_bringup.cli.errors import UsageError
from rm_bringup.cli.main import build_parser


def selection(*argv):
    return selection_from_args(build_parser().parse_args(['bag', 'record', *argv]))


def test_listed_topics_only_and_names_made_absolute():
    chosen = selection('chassis_cmd', '--topics', '/odom')
    assert chosen.wants('/chassis_cmd') and chosen.wants('/odom')
    assert not chosen.wants('/rosout')


def test_all_skips_hidden_topics_unless_asked():
    assert selection('-a').wants('/rosout')
    assert not selection('-a').wants('/_internal/x')
    assert selection('-a', '--include-hidden-topics').wants('/_internal/x')


def test_regex_matches_anywhere_in_the_name_and_exclusions_win():
    chosen = selection('-e', 'cmd', '--exclude-regex', '^/gimbal', '--exclude-topics', '/shoot_cmd')
    assert chosen.wants('/chassis_cmd')
    assert not chosen.wants('/gimbal_cmd')
    assert not chosen.wants('/shoot_cmd')
    assert not chosen.wants('/odom')


def test_explicit_topic_is_recorded_even_if_hidden():
    assert TopicSelection(topics=frozenset({'/_x'})).wants('/_x')


def test_exclusion_needs_all_or_regex():
    with pytest.raises(UsageError, match='need --all'):
        selection('/odom', '--exclude-regex', 'x')


def test_bad_regex_is_a_usage_error():
    with pytest.raises(UsageError, match=re.escape("invalid regular expression '(")):
        selection('-e', '(')
