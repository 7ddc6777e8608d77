"""Replay a scenario's command bag into the simulated robot and record what it does.

Why one module: recording, replaying and the result views serve one call, replay().

    result = replay(SCENARIOS['square'], output=tmp_path / 'square_out')
    result.body[-1].x            # sim ground truth at the end
    result.messages('/odom')     # what the robot published, in order

What happens:

1. A LockstepRobot (support.lockstep) is built from the scenario's robot (config,
   plugins, overrides): the loop, the plugins and rm_sim stepped together on a simulated
   clock, so a replay gives the same numbers on every run, whatever the machine's load.
2. The bag (test/data/<scenario>/ unless given) is read with rmcli's reader
   (``rm_bringup.cli.bag_io``; a type recorded with an older definition is rebuilt in the
   installed one, as ``rmcli bag play`` does) and each message is handed to the plugins
   subscribed to its topic (renamed by the scenario's ``remaps``, parsed as ``rmcli bag
   play --remap`` parses them) at its bag time on the simulated clock, through the
   callbacks their subscriptions run. Every std_msgs/Header in a command is stamped with the robot's
   ROS clock at that moment, as a live commander's would be (the bags carry stamps
   relative to their start; played with plain ``rmcli bag play`` into a live robot, they
   would be rejected as stale).
3. While playing and for the scenario's ``tail_s`` after it, the sim's ground truth is
   sampled every SAMPLE_PERIOD_S (chassis pose and twist, gimbal joint angles) and the
   scenario's faults are applied at their bag times (Jam: lock the motor at its next
   drive forward, free it when it pushes back for a while).
4. The result holds every output message and body sample against the *replay clock*
   (simulated time since playback start, in seconds: the bag's own time axis), plus the
   commands as they were handed over. With ``output`` everything is also written to a
   rosbag2 (MCAP) bag -- the commands, the outputs, the sim body as nav_msgs/Odometry on
   /sim/body and its gimbal joints as sensor_msgs/JointState on /sim/gimbal, stamped with
   the receive (sample) time -- so ``rmcli bag plot`` can draw it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from replay.scenarios import DATA_DIR, Jam, Scenario, headers

SAMPLE_PERIOD_S = 0.01  # [s] ground-truth sampling and fault checks (simulated time)
SIM_BODY_TOPIC = '/sim/body'
SIM_GIMBAL_TOPIC = '/sim/gimbal'

# The robot's outputs a scenario can record: (topic, message type).
OUTPUTS: tuple[tuple[str, str], ...] = (
    ('/odom', 'nav_msgs/msg/Odometry'),
    ('/chassis_state', 'rm_msgs/msg/ChassisState'),
    ('/gimbal_state', 'rm_msgs/msg/GimbalState'),
    ('/shooter_state', 'rm_msgs/msg/ShooterState'),
    ('/actuator_states', 'rm_msgs/msg/ActuatorState'),
    ('/imu', 'sensor_msgs/msg/Imu'),
)


class ReplayError(RuntimeError):
    """The replay could not run as the scenario says (a topic nobody subscribes)."""


@dataclass(frozen=True)
class Received:
    """One message the robot published, with when it arrived."""

    t: float  # [s] replay clock (sim time since playback start)
    stamp_ns: int  # ROS time of arrival [ns]
    msg: Any


@dataclass(frozen=True)
class Sent:
    """One command as published (with its rewritten stamps)."""

    t: float  # [s] replay clock
    bag_t: float  # [s] its time in the bag
    stamp_ns: int  # ROS time it was published with [ns]
    msg: Any


@dataclass(frozen=True)
class BodySample:
    """Sim ground truth: chassis pose in the world, its twist, the gimbal joints."""

    t: float  # [s] replay clock
    stamp_ns: int  # ROS time of the sample [ns]
    x: float  # [m]
    y: float  # [m]
    yaw: float  # [rad] unwrapped
    vx: float  # [m/s] base_link
    vy: float  # [m/s]
    wz: float  # [rad/s]
    gimbal_yaw: float  # [rad] yaw joint angle relative to the chassis
    gimbal_pitch: float  # [rad]

    @property
    def barrel_yaw(self) -> float:
        """World heading of the barrel [rad], unwrapped: chassis yaw + yaw joint."""
        return self.yaw + self.gimbal_yaw


@dataclass(frozen=True)
class FaultRecord:
    """A fault the harness applied or cleared."""

    t: float  # [s] replay clock
    motor: str
    action: str  # 'armed' | 'wedged' (locked) | 'clear'
    detail: str


@dataclass
class ReplayResult:
    """Everything a replay recorded; times on the replay clock unless named wall."""

    scenario: Scenario
    received: dict[str, list[Received]]
    sent: dict[str, list[Sent]]
    body: list[BodySample]
    faults: list[FaultRecord]
    played: int  # messages of the bag handed over
    duration_s: float  # replay clock at the end of the recording [s]
    wall_s: float  # wall time from playback start to the end of the recording [s]
    output: Path | None = None
    parameters: dict[str, dict[str, Any]] = field(default_factory=dict)

    def samples(self, topic: str) -> list[Received]:
        """Every message received on topic (empty if none)."""
        return self.received.get(topic, [])

    def messages(self, topic: str) -> list[Any]:
        """The messages received on topic, in order."""
        return [r.msg for r in self.samples(topic)]

    def last(self, topic: str) -> Any:
        """The last message received on topic.

        Raises:
            ReplayError: nothing was received on it.
        """
        samples = self.samples(topic)
        if not samples:
            raise ReplayError(f'no message on {topic} during the replay')
        return samples[-1].msg

    def body_between(self, t0: float, t1: float = math.inf) -> list[BodySample]:
        """Body samples with t0 <= t <= t1 [s, replay clock]."""
        return [s for s in self.body if t0 <= s.t <= t1]

    def last_sent(self, topic: str) -> Sent:
        """The last command handed over on topic."""
        return self.sent[topic][-1]

    def summary(self) -> str:
        """One line: played, durations, what was received."""
        counts = ', '.join(f'{t} {len(r)}' for t, r in self.received.items() if r)
        return (
            f'{self.scenario.name}: played {self.played} messages; {self.duration_s:.2f} s '
            f'sim in {self.wall_s:.2f} s wall; received {counts}'
        )


def bag_path(scenario: Scenario) -> Path:
    """The committed bag of a scenario."""
    return DATA_DIR / scenario.name


class _Faults:
    """Applies a scenario's faults at their bag times (called every sample)."""

    def __init__(self, world: Any, faults: tuple[Jam, ...]) -> None:
        self._world = world
        self._pending = sorted(faults, key=lambda f: f.at_s)
        self._armed: list[Jam] = []
        self._wedged: dict[Jam, float | None] = {}  # jam -> since when it is pushed back
        self.records: list[FaultRecord] = []

    def update(self, t: float) -> None:
        """Arm, lock and free the jams at replay clock t [s]."""
        from rm_base.sim import Fault, FaultKind

        while self._pending and self._pending[0].at_s <= t:
            jam = self._pending.pop(0)
            self._armed.append(jam)
            self.records.append(FaultRecord(t, jam.motor, 'armed', 'jam at the next push'))
        for jam in list(self._armed):
            torque, speed = self._motor(jam.motor)
            if torque >= jam.torque and speed >= jam.speed:
                self._world.inject(jam.motor, Fault.jam())
                self._armed.remove(jam)
                self._wedged[jam] = None
                self.records.append(
                    FaultRecord(
                        t, jam.motor, 'wedged', f'locked at {speed:.1f} rad/s, {torque:.2f} N*m'
                    )
                )
        for jam, since in list(self._wedged.items()):
            torque, _ = self._motor(jam.motor)
            if torque > -jam.torque:
                self._wedged[jam] = None
            elif since is None:
                self._wedged[jam] = t
            elif t - since >= jam.free_s:
                self._world.clear_faults(jam.motor, FaultKind.JAM)
                del self._wedged[jam]
                detail = f'pushed back ({torque:.2f} N*m) for {t - since:.3f} s'
                self.records.append(FaultRecord(t, jam.motor, 'clear', detail))

    def _motor(self, motor: str) -> tuple[float, float]:
        """Torque [N*m] and speed [rad/s] of a simulated motor at its output shaft."""
        model = self._world.motor(motor).model
        return model.torque, model.velocity


def _sample_body(world: Any, t: float, stamp_ns: int) -> BodySample:
    b = world.body
    vx, vy, wz = b.twist
    return BodySample(t, stamp_ns, b.x, b.y, b.yaw, vx, vy, wz, b.gimbal_yaw, b.gimbal_pitch)


def replay(
    scenario: Scenario,
    *,
    bag: Path | None = None,
    output: Path | None = None,
    record: tuple[str, ...] | None = None,
) -> ReplayResult:
    """Play a scenario's bag into a fresh LockstepRobot and record the outcome (module doc).

    Args:
        scenario: what to build and do (robot, faults, tail).
        bag: the command bag (default: test/data/<scenario.name>).
        output: write commands, outputs and the sim body into a new bag here.
        record: the robot's output topics to record (OUTPUTS); default the scenario's.

    Raises:
        ReplayError: an unknown output, or a bag topic no plugin subscribes.
    """
    from rclpy.serialization import deserialize_message
    from rm_bringup.cli.bag_convert import read_installed
    from rm_bringup.cli.bag_io import open_bag
    from rm_bringup.cli.bag_topics import parse_remaps
    from rm_bringup.cli.interfaces import get_message_class
    from support.lockstep import LockstepRobot

    bag = bag_path(scenario) if bag is None else Path(bag)
    setup = scenario.robot
    topics = scenario.record if record is None else record
    unknown = sorted(set(topics) - {topic for topic, _ in OUTPUTS})
    if unknown:
        raise ReplayError(f'cannot record {unknown}: the outputs are {sorted(dict(OUTPUTS))}')
    remaps = parse_remaps(list(scenario.remaps))
    with open_bag(bag) as reader:
        classes = {c.topic: get_message_class(c.msgtype) for c in reader.connections}
        start_ns = reader.start_time
        schedule = [
            (stamp - start_ns, remaps.get(c.topic, c.topic),
             deserialize_message(raw, classes[c.topic]))
            for c, stamp, raw in read_installed(reader, bag, list(reader.connections),
                                                start=start_ns)
        ]
    wall0 = time.monotonic()
    with LockstepRobot(setup.config, plugins=tuple(setup.plugins),
                       overrides=setup.overrides) as robot:
        world = robot.world
        received: dict[str, list[Received]] = {topic: [] for topic in topics}
        t0_ns = world.time_ns

        def replay_t() -> float:
            return (world.time_ns - t0_ns) * 1e-9

        for topic in topics:
            log = received[topic]
            robot.host.add_local_handler(
                topic, lambda msg, now_ns, log=log: log.append(Received(replay_t(), now_ns, msg))
            )
            if topic in ('/actuator_states', '/joint_states'):
                robot.watch(topic, keep_history=False)
                robot.on_tick(_forward_bridge_states(robot, topic, log, replay_t))
        sent: dict[str, list[Sent]] = {remaps.get(topic, topic): [] for topic in classes}
        faults = _Faults(world, scenario.faults)
        body: list[BodySample] = []
        end_ns = round((scenario.end_s + scenario.tail_s) * 1e9)
        sample_ticks = round(SAMPLE_PERIOD_S * 1e9 / world.period_ns)
        pending = iter(schedule)
        upcoming = next(pending, None)
        while world.time_ns - t0_ns <= end_ns:
            elapsed_ns = world.time_ns - t0_ns
            while upcoming is not None and upcoming[0] <= elapsed_ns:
                offset_ns, topic, msg = upcoming
                now = robot.host.get_clock().now()
                for header in headers(msg):
                    header.stamp = now.to_msg()
                if robot.host.inject(topic, msg) == 0:
                    raise ReplayError(f'{scenario.name}: no plugin subscribes {topic}')
                sent[topic].append(Sent(replay_t(), offset_ns * 1e-9, now.nanoseconds, msg))
                upcoming = next(pending, None)
            if robot.ticks % sample_ticks == 0:
                t = replay_t()
                body.append(_sample_body(world, t, robot.now_ns))
                faults.update(t)
            robot.step()
        result = ReplayResult(
            scenario=scenario,
            received=received,
            sent=sent,
            body=body,
            faults=faults.records,
            played=len(schedule),
            duration_s=replay_t(),
            wall_s=time.monotonic() - wall0,
            parameters={'can_bridge': robot.bridge_parameters, 'rm_robot': robot.host_parameters},
        )
    if output is not None:
        result.output = write_output_bag(result, Path(output))
    return result


def _forward_bridge_states(
    robot: Any, topic: str, log: list[Received], replay_t: Callable[[], float]
) -> Callable[[], None]:
    """A tick hook that records each new message of a bridge state topic."""
    last: list[Any] = [None]

    def forward() -> None:
        msg = robot.latest(topic)
        if msg is not last[0]:
            last[0] = msg
            log.append(Received(replay_t(), robot.now_ns, msg))

    return forward


def _records(result: ReplayResult, store: Any) -> Iterator[tuple[str, str, int, bytes]]:
    """(topic, msgtype, ROS time [ns], CDR) of everything a replay recorded.

    The robot's messages and the commands are serialized by rclpy, as a recorder would
    store them; the sim's ground truth is built and serialized with the rosbags
    typestore (rclpy pads empty float64 sequences in a way rosbags does not read back).
    """
    from rclpy.serialization import serialize_message
    from rm_bringup.cli.interfaces import type_name_of

    for topic, logged in (*result.sent.items(), *result.received.items()):
        for item in logged:
            msgtype = type_name_of(type(item.msg))
            yield topic, msgtype, item.stamp_ns, serialize_message(item.msg)
    for b in result.body:
        for topic, msgtype, msg in _ground_truth(b, store):
            yield topic, msgtype, b.stamp_ns, bytes(store.serialize_cdr(msg, msgtype))


def _ground_truth(sample: BodySample, store: Any) -> list[tuple[str, str, Any]]:
    """A body sample as rosbags messages for SIM_BODY_TOPIC and SIM_GIMBAL_TOPIC.

    nav_msgs/Odometry: odom -> base_link, twist in base_link; sensor_msgs/JointState: the
    gimbal's yaw and pitch joint angles [rad].
    """
    import numpy as np
    from rm_base.geometry import quaternion_from_yaw

    t = store.types

    def header(frame_id: str) -> Any:
        stamp = t['builtin_interfaces/msg/Time'](
            sec=sample.stamp_ns // 10**9, nanosec=sample.stamp_ns % 10**9
        )
        return t['std_msgs/msg/Header'](stamp=stamp, frame_id=frame_id)

    def vector(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
        return t['geometry_msgs/msg/Vector3'](x=x, y=y, z=z)

    qx, qy, qz, qw = quaternion_from_yaw(sample.yaw)
    pose = t['geometry_msgs/msg/Pose'](
        position=t['geometry_msgs/msg/Point'](x=sample.x, y=sample.y, z=0.0),
        orientation=t['geometry_msgs/msg/Quaternion'](x=qx, y=qy, z=qz, w=qw),
    )
    twist = t['geometry_msgs/msg/Twist'](
        linear=vector(sample.vx, sample.vy), angular=vector(z=sample.wz)
    )
    odometry = t['nav_msgs/msg/Odometry'](
        header=header('odom'),
        child_frame_id='base_link',
        pose=t['geometry_msgs/msg/PoseWithCovariance'](pose=pose, covariance=np.zeros(36)),
        twist=t['geometry_msgs/msg/TwistWithCovariance'](twist=twist, covariance=np.zeros(36)),
    )
    joints = t['sensor_msgs/msg/JointState'](
        header=header(''),
        name=['yaw', 'pitch'],
        position=np.array([sample.gimbal_yaw, sample.gimbal_pitch]),
        velocity=np.zeros(0),
        effort=np.zeros(0),
    )
    return [
        (SIM_BODY_TOPIC, 'nav_msgs/msg/Odometry', odometry),
        (SIM_GIMBAL_TOPIC, 'sensor_msgs/msg/JointState', joints),
    ]


def write_output_bag(result: ReplayResult, path: Path) -> Path:
    """Write a replay's commands, outputs and sim ground truth into a new rosbag2 (MCAP)."""
    from rm_bringup.cli.bag_types import BagTypes
    from rosbags.rosbag2 import StoragePlugin, Writer

    types = BagTypes()
    records = sorted(_records(result, types.typestore), key=lambda r: r[2])
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {}
        for topic, msgtype, stamp_ns, cdr in records:
            if topic not in connections:
                types.ensure(msgtype)
                connections[topic] = writer.add_connection(
                    topic, msgtype, typestore=types.typestore
                )
            writer.write(connections[topic], stamp_ns, cdr)
    return path
