"""QoS: ros2cli's option keys, adapting to publishers, bag metadata both ways."""

import argparse

import pytest
from rclpy.duration import Duration
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    LivelinessPolicy,
    QoSPresetProfiles,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
)
from rm_bringup.cli import qos
from rosbags.interfaces import QosDurability, QosHistory, QosReliability, QosTime


def test_option_keys_are_rclpys_short_keys():
    # Spelled out in qos.py so the parser builds without rclpy; they must not drift.
    assert list(qos.PROFILE_KEYS) == list(QoSPresetProfiles.short_keys())
    assert list(qos.HISTORY_KEYS) == list(HistoryPolicy.short_keys())
    assert list(qos.RELIABILITY_KEYS) == list(ReliabilityPolicy.short_keys())
    assert list(qos.DURABILITY_KEYS) == list(DurabilityPolicy.short_keys())


def parse(argv, default='default'):
    parser = argparse.ArgumentParser()
    qos.add_qos_arguments(parser, 'publish', default)
    return parser.parse_args(argv)


def test_profile_from_options_overrides_the_preset_and_leaves_it_alone():
    profile = qos.profile_from_args(
        parse(['--qos-profile', 'sensor_data', '--qos-reliability', 'reliable', '--qos-depth', '3'])
    )
    assert profile.reliability == ReliabilityPolicy.RELIABLE
    assert profile.depth == 3
    assert qos_profile_sensor_data.reliability == ReliabilityPolicy.BEST_EFFORT
    assert qos_profile_sensor_data.depth == 5


def test_qos_overridden_only_for_single_policies():
    assert not qos.qos_overridden(parse(['--qos-profile', 'sensor_data']))
    assert qos.qos_overridden(parse(['--qos-durability', 'transient_local']))


def offer(reliability, durability=DurabilityPolicy.VOLATILE):
    return QoSProfile(depth=1, reliability=reliability, durability=durability)


def test_all_reliable_publishers_get_a_reliable_subscription():
    profile, warnings = qos.adapt_to_publishers(
        qos_profile_sensor_data, [offer(ReliabilityPolicy.RELIABLE)] * 2
    )
    assert profile.reliability == ReliabilityPolicy.RELIABLE
    assert profile.durability == DurabilityPolicy.VOLATILE
    assert warnings == []


def test_mixed_reliability_falls_back_to_best_effort_with_a_warning():
    profile, warnings = qos.adapt_to_publishers(
        QoSProfile(depth=10),
        [offer(ReliabilityPolicy.RELIABLE), offer(ReliabilityPolicy.BEST_EFFORT)],
    )
    assert profile.reliability == ReliabilityPolicy.BEST_EFFORT
    assert len(warnings) == 1 and 'RELIABLE' in warnings[0]


def test_all_latched_publishers_get_a_transient_local_subscription():
    latched = offer(ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
    profile, _ = qos.adapt_to_publishers(QoSProfile(depth=10), [latched])
    assert profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
    mixed, warnings = qos.adapt_to_publishers(
        QoSProfile(depth=10), [latched, offer(ReliabilityPolicy.RELIABLE)]
    )
    assert mixed.durability == DurabilityPolicy.VOLATILE and warnings


def test_no_publishers_keep_the_base_profile():
    profile, _ = qos.adapt_to_publishers(qos_profile_sensor_data, [])
    assert profile.reliability == ReliabilityPolicy.BEST_EFFORT


def test_infinite_durations_are_written_as_rosbag2_writes_rmw_duration_infinite():
    # An endpoint's infinite deadline comes back from rmw as INT64_MAX ns:
    # 9223372036854775807 ns = 9223372036 s + 854775807 ns.
    profile = QoSProfile(
        depth=0, history=HistoryPolicy.UNKNOWN, reliability=ReliabilityPolicy.RELIABLE
    )
    profile.deadline = Duration(nanoseconds=2**63 - 1)
    bag = qos.to_bag_qos(profile)
    assert bag.deadline == QosTime(9223372036, 854775807)
    assert bag.reliability == QosReliability.RELIABLE
    assert bag.history == QosHistory.UNKNOWN


def test_recorded_offer_is_replayed_with_its_policies():
    recorded = QoSProfile(
        depth=1,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
        liveliness=LivelinessPolicy.AUTOMATIC,
        deadline=Duration(seconds=2),
    )
    bag = qos.to_bag_qos(recorded)
    assert bag.durability == QosDurability.TRANSIENT_LOCAL
    played = qos.offer_for_recorded([bag, bag])
    assert played.reliability == ReliabilityPolicy.RELIABLE
    assert played.durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert played.deadline == Duration(seconds=2)
    assert played.history == HistoryPolicy.KEEP_LAST and played.depth == 10


def test_disagreeing_recorded_offers_replay_with_the_default():
    reliable = qos.to_bag_qos(QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE))
    best_effort = qos.to_bag_qos(
        QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.BEST_EFFORT,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
    )
    played = qos.offer_for_recorded([reliable, best_effort])
    assert played.reliability == ReliabilityPolicy.RELIABLE
    assert played.durability == DurabilityPolicy.VOLATILE


@pytest.mark.parametrize('sec_nsec', [(9223372036, 854775807), (0x7FFFFFFF, 0xFFFFFFFF), (0, 0)])
def test_infinite_or_unset_recorded_durations_are_left_unset(sec_nsec):
    bag = qos.to_bag_qos(QoSProfile(depth=1))._replace(deadline=QosTime(*sec_nsec))
    assert qos.offer_for_recorded([bag]).deadline == Duration()
