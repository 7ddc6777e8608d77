"""QoS for the rmcli verbs: ros2cli's --qos-* options, adapting to publishers, bag metadata.

The adapting rules are those of ``ros2 topic echo`` and ``ros2 bag record``
(rosbag2_storage ``adapt_request_to_offers``): ask for RELIABLE only if every publisher
offers it, TRANSIENT_LOCAL only if every publisher offers it, so one subscription matches
all publishers. Playback offers what was recorded when all recorded publishers agreed
(``adapt_offer_to_recorded_offers``).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rclpy.qos import QoSProfile
    from rosbags.interfaces import Qos, QosTime

# The short keys of rclpy 7.1 (Jazzy); test_qos checks them against rclpy itself. Spelled
# out so that building the parser (rmcli --help, bag info) does not import rclpy.
PROFILE_KEYS = (
    'unknown',
    'default',
    'system_default',
    'sensor_data',
    'services_default',
    'parameters',
    'parameter_events',
    'action_status_default',
    'best_available',
)
HISTORY_KEYS = ('system_default', 'keep_last', 'keep_all', 'unknown')
RELIABILITY_KEYS = ('system_default', 'reliable', 'best_effort', 'unknown', 'best_available')
DURABILITY_KEYS = ('system_default', 'transient_local', 'volatile', 'unknown', 'best_available')

# rmw's infinite duration as rosbag2 writes it (RMW_DURATION_INFINITE = INT64_MAX ns), and
# the 'infinity' Foxy-era RMWs reported, which rosbag2 also reads as infinite.
_INFINITE_NS = 2**63 - 1
_FOXY_INFINITE_SEC = 0x7FFFFFFF
_DEFAULT_DEPTH = 10


def add_qos_arguments(parser: argparse.ArgumentParser, verb: str, default_profile: str) -> None:
    """Add ros2cli's ``--qos-profile/-depth/-history/-reliability/-durability`` options."""
    parser.add_argument(
        '--qos-profile',
        choices=PROFILE_KEYS,
        default=default_profile,
        help=f'Quality of service preset profile to {verb} with (default: {default_profile})',
    )
    parser.add_argument(
        '--qos-depth',
        metavar='N',
        type=int,
        default=None,
        help=f'Queue size setting to {verb} with (overrides depth value of --qos-profile option)',
    )
    for name, keys in (
        ('history', HISTORY_KEYS),
        ('reliability', RELIABILITY_KEYS),
        ('durability', DURABILITY_KEYS),
    ):
        parser.add_argument(
            f'--qos-{name}',
            choices=keys,
            default=None,
            help=f'Quality of service {name} setting to {verb} with '
            f'(overrides {name} value of --qos-profile option)',
        )


def qos_overridden(args: argparse.Namespace) -> bool:
    """Whether any single policy was given on the command line."""
    return any(
        getattr(args, f'qos_{name}') is not None
        for name in ('depth', 'history', 'reliability', 'durability')
    )


def profile_from_args(args: argparse.Namespace) -> QoSProfile:
    """Return a new QoSProfile from the --qos-* options."""
    from rclpy.qos import (
        DurabilityPolicy,
        HistoryPolicy,
        QoSPresetProfiles,
        ReliabilityPolicy,
    )

    profile = copy_profile(QoSPresetProfiles.get_from_short_key(args.qos_profile))
    if args.qos_history is not None:
        profile.history = HistoryPolicy.get_from_short_key(args.qos_history)
    if args.qos_depth is not None:
        profile.depth = args.qos_depth
    if args.qos_reliability is not None:
        profile.reliability = ReliabilityPolicy.get_from_short_key(args.qos_reliability)
    if args.qos_durability is not None:
        profile.durability = DurabilityPolicy.get_from_short_key(args.qos_durability)
    return profile


def copy_profile(profile: QoSProfile) -> QoSProfile:
    """Return an independent copy (the presets are shared objects)."""
    from rclpy.qos import QoSProfile

    return QoSProfile(
        history=profile.history,
        depth=profile.depth,
        reliability=profile.reliability,
        durability=profile.durability,
        lifespan=profile.lifespan,
        deadline=profile.deadline,
        liveliness=profile.liveliness,
        liveliness_lease_duration=profile.liveliness_lease_duration,
        avoid_ros_namespace_conventions=profile.avoid_ros_namespace_conventions,
    )


def adapt_to_publishers(
    base: QoSProfile, offered: Sequence[QoSProfile]
) -> tuple[QoSProfile, list[str]]:
    """Return base adapted so that it matches every offered profile, and any warnings.

    Args:
        base: profile to start from (not changed).
        offered: QoS of the publishers currently on the topic; none leaves base as is.
    """
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

    profile = copy_profile(base)
    warnings: list[str] = []
    if not offered:
        return profile, warnings
    reliable = sum(p.reliability == ReliabilityPolicy.RELIABLE for p in offered)
    latched = sum(p.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in offered)
    if reliable == len(offered):
        profile.reliability = ReliabilityPolicy.RELIABLE
    else:
        if reliable:
            warnings.append(
                'some, but not all, publishers offer RELIABLE; using BEST_EFFORT to match all'
            )
        profile.reliability = ReliabilityPolicy.BEST_EFFORT
    if latched == len(offered):
        profile.durability = DurabilityPolicy.TRANSIENT_LOCAL
    else:
        if latched:
            warnings.append(
                'some, but not all, publishers offer TRANSIENT_LOCAL; using VOLATILE to match all'
            )
        profile.durability = DurabilityPolicy.VOLATILE
    return profile, warnings


def _bag_time(duration) -> QosTime:
    from rosbags.interfaces import QosTime

    sec, nsec = divmod(duration.nanoseconds, 10**9)
    return QosTime(sec, nsec)


def to_bag_qos(profile: QoSProfile) -> Qos:
    """Convert an rclpy QoSProfile (e.g. a publisher's offer) to the rosbags metadata type."""
    from rosbags.interfaces import (
        Qos,
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
    )

    def member(enum, policy):
        return enum.__members__.get(policy.name, enum.UNKNOWN)

    return Qos(
        history=member(QosHistory, profile.history),
        depth=profile.depth,
        reliability=member(QosReliability, profile.reliability),
        durability=member(QosDurability, profile.durability),
        deadline=_bag_time(profile.deadline),
        lifespan=_bag_time(profile.lifespan),
        liveliness=member(QosLiveliness, profile.liveliness),
        liveliness_lease_duration=_bag_time(profile.liveliness_lease_duration),
        avoid_ros_namespace_conventions=profile.avoid_ros_namespace_conventions,
    )


def _finite(time: QosTime):
    """Rclpy Duration for a recorded time, or None when it means 'infinite'/'unset'."""
    from rclpy.duration import Duration

    total_ns = time.sec * 10**9 + time.nsec
    if total_ns == 0 or total_ns >= _INFINITE_NS or time.sec >= _FOXY_INFINITE_SEC:
        return None
    return Duration(seconds=time.sec, nanoseconds=time.nsec)


def _compatibility_key(qos: Qos) -> tuple:
    return (
        qos.reliability,
        qos.durability,
        qos.deadline,
        qos.liveliness,
        qos.liveliness_lease_duration,
    )


def offer_for_recorded(recorded: Sequence[Qos]) -> QoSProfile:
    """Return the QoS to publish a recorded topic with (rosbag2's play rule).

    The recorded offer when all recorded publishers agreed on the policies that affect
    matching (history reset to keep_last 10), else the default (reliable, volatile).
    """
    from rclpy.qos import (
        DurabilityPolicy,
        LivelinessPolicy,
        QoSProfile,
        ReliabilityPolicy,
    )

    profile = QoSProfile(depth=_DEFAULT_DEPTH)
    if not recorded or len({_compatibility_key(q) for q in recorded}) != 1:
        return profile
    first = recorded[0]
    if first.reliability.name in ('RELIABLE', 'BEST_EFFORT'):
        profile.reliability = ReliabilityPolicy[first.reliability.name]
    if first.durability.name in ('TRANSIENT_LOCAL', 'VOLATILE'):
        profile.durability = DurabilityPolicy[first.durability.name]
    if first.liveliness.name in ('AUTOMATIC', 'MANUAL_BY_TOPIC'):
        profile.liveliness = LivelinessPolicy[first.liveliness.name]
    for name in ('deadline', 'lifespan', 'liveliness_lease_duration'):
        duration = _finite(getattr(first, name))
        if duration is not None:
            setattr(profile, name, duration)
    return profile
