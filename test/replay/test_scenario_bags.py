"""The committed scenario bags (test/data) are what scripts/make_scenario_bags.py writes.

No ROS node here: bags are read with rmcli's bag helpers (rosbags) and messages compared
as decoded messages, never as bytes.
"""

from __future__ import annotations

import importlib.util
import itertools
import pathlib

import pytest
from rm_bringup.cli.bag_convert import read_installed
from rm_bringup.cli.bag_io import open_bag
from rm_bringup.cli.bag_types import rm_bag_types

from replay.scenarios import DATA_DIR, SCENARIOS, Command, Robot, Scenario

ROOT = pathlib.Path(__file__).resolve().parents[2]
MAX_DATA_BYTES = 300 * 1024  # test/data stays small: a few hundred KB at most


@pytest.fixture(scope='module')
def generator():
    spec = importlib.util.spec_from_file_location(
        'make_scenario_bags', ROOT / 'scripts' / 'make_scenario_bags.py'
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope='module')
def store():
    return rm_bag_types().typestore


def decoded(path, store):
    """(topic -> msgtype, [(topic, log time [ns], decoded message)]) of a bag."""
    with open_bag(path) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        messages = [
            (c.topic, t, store.deserialize_cdr(raw, c.msgtype))
            for c, t, raw in read_installed(reader, path)
        ]
    return types, messages


@pytest.mark.parametrize('name', sorted(SCENARIOS))
def test_the_committed_bag_holds_the_messages_of_its_scenario(name, generator, store, tmp_path):
    committed = DATA_DIR / name
    assert (committed / 'metadata.yaml').is_file(), (
        f'missing {committed}: run scripts/make_scenario_bags.py'
    )
    fresh = generator.write_bag(SCENARIOS[name], tmp_path / name)
    committed_types, committed_messages = decoded(committed, store)
    fresh_types, fresh_messages = decoded(fresh, store)
    assert committed_types == fresh_types == dict(SCENARIOS[name].topics)
    assert len(committed_messages) == len(fresh_messages)
    assert committed_messages == fresh_messages, (
        f'{committed} is stale: run scripts/make_scenario_bags.py {name}'
    )


@pytest.mark.parametrize('name', sorted(SCENARIOS))
def test_commands_stream_at_the_rate_with_stamps_from_the_bag_start(name, store):
    scenario = SCENARIOS[name]
    _, messages = decoded(DATA_DIR / name, store)
    assert messages[0][1] == 0  # the bag starts at 0 s
    periods = {}
    for topic, _ in scenario.topics:  # each topic at its own rate (50 Hz unless said)
        rate = next(c.rate_hz for c in scenario.commands if c.topic == topic)
        periods[topic] = period_ns = round(1e9 / rate)
        times = [t for tp, t, _ in messages if tp == topic]
        assert {b - a for a, b in itertools.pairwise(times)} == {period_ns}, topic
    period_ns = max(periods.values())
    for _, t, msg in messages:
        if hasattr(msg, 'header'):
            assert msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec == t
    last = max(t for _, t, _ in messages)
    assert last == pytest.approx(scenario.end_s * 1e9, abs=period_ns + 5e6)


def test_the_square_bag_commands_four_legs_that_cancel(store):
    _, messages = decoded(DATA_DIR / 'square', store)
    twists = [(m.linear.x, m.linear.y) for topic, _, m in messages if topic == '/vel_cmd']
    # Four legs: runs of the same non-zero velocity, forward, left, back, right at 1 m/s,
    # each 1 s of 20 ms messages: 50 messages.
    legs = [(v, len(list(run))) for v, run in itertools.groupby(twists) if v != (0.0, 0.0)]
    assert legs == [((1.0, 0.0), 50), ((0.0, 1.0), 50), ((-1.0, 0.0), 50), ((0.0, -1.0), 50)]
    assert {m.mode for topic, _, m in messages if topic == '/chassis_cmd'} == {1}  # RAW


def test_the_test_data_stays_small():
    size = sum(p.stat().st_size for p in DATA_DIR.rglob('*') if p.is_file())
    assert size < MAX_DATA_BYTES, f'test/data holds {size / 1024:.0f} KiB'


def test_when_two_streams_of_a_topic_overlap_expect_an_error():
    overlapping = Scenario(
        name='bad',
        description='',
        robot=Robot(plugins=()),
        commands=(
            Command('/vel_cmd', 'geometry_msgs/msg/Twist', {}, 0.0, 1.0),
            Command('/vel_cmd', 'geometry_msgs/msg/Twist', {}, 0.5, 1.5),
        ),
    )
    with pytest.raises(ValueError, match=r'bad: commands on /vel_cmd overlap at 0.5 s'):
        list(overlapping.timeline())
