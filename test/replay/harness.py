"""Replay a scenario's command bag into the simulated robot and record what it does.

    result = replay(SCENARIOS['square'], output=tmp_path / 'square_out')
    result.body[-1].x            # sim ground truth at the end
    result.messages('/odom')     # what the robot published, in order

What happens:

1. A SimRobot (support.robot) is built from the scenario's robot (config, plugins,
   overrides); the harness subscribes to the outputs the scenario records (of OUTPUTS)
   and waits until every loaded plugin reports its state (READY_TOPICS) with little
   delay (READY_LATENCY_S: the robot's one executor has no backlog) and every command
   topic is matched both ways.
2. The bag (test/data/<scenario>/ unless given) is played with rmcli's own playback
   (``rm_bringup.cli.bag_play.play``: the bag's order and relative timing, absolute
   deadlines), into publishers with the QoS the bag recorded (rmcli's rule). Three things
   differ from ``rmcli bag play``, all in what the harness hands play() as publishers:

   - **Stamps are rewritten.** The bags carry header stamps relative to the bag start
     (0 s at the first message); the plugins time their command watchdogs from the stamp
     and reject stale commands, so every std_msgs/Header in a command is stamped with the
     robot's ROS clock (now) at the moment it is published, as a live commander's would be.
     Played with plain ``rmcli bag play`` into a live robot, these bags' commands are
     rejected as stale.
   - **Pacing follows the simulator.** A message goes out at its bag time on the wall
     clock (play()) *and* not before the simulated world has advanced by as much since
     playback started. Under CPU starvation the simulator lets its time slip behind the
     wall clock (rm_base.sim.SimWorld); paced on the wall clock alone, a leg commanded for
     1 s would move the robot for only part of that, by an amount that changes with the
     load. With a quiet machine both clocks agree and the pacing is rmcli's.
   - **The stream stays live.** While the sim holds a message back, a live commander
     would still be sending its current command at its rate; the plugins' watchdogs run
     on the wall clock and would otherwise see the slowed stream as a dropout. So while
     a topic's stream continues in the bag (its next message follows within 1.5 of its
     periods), its last message is sent again, freshly stamped, whenever REFRESH_PERIODS
     of its periods of wall time pass without one (``Sent.refresh``): often enough for
     any watchdog (60 ms at 50 Hz, a quarter of the shortest command timeout), rarely
     enough not to add much work to a machine that is already too slow. Where the bag's
     stream ends or pauses, nothing is sent: dropouts in the bag reach the robot as is.

3. While playing and for the scenario's ``tail_s`` after it, a sampler thread reads the
   sim's ground truth every SAMPLE_PERIOD_S (chassis pose and twist, gimbal joint angles)
   and applies the scenario's faults at their bag times (Jam: lock the motor at its next
   drive forward, free it when it pushes back for a while).
4. The result holds every output message and body sample against the *replay clock*
   (simulated time since playback start, in seconds: the bag's own time axis), plus the
   commands as they were published. With ``output`` everything is also written to a
   rosbag2 (MCAP) bag -- the commands, the outputs, the sim body as nav_msgs/Odometry on
   /sim/body and its gimbal joints as sensor_msgs/JointState on /sim/gimbal, stamped with
   the receive (sample) time -- so ``rmcli bag plot`` can draw it.
"""

from __future__ import annotations

import itertools
import math
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from replay.scenarios import DATA_DIR, Jam, Scenario, headers

SAMPLE_PERIOD_S = 0.01  # [s] ground-truth sampling and fault checks (wall clock)
REFRESH_PERIODS = 3  # a held-back stream is refreshed after this many of its periods
READY_TIMEOUT_S = 20.0  # [s] for the plugins' first states and the subscriptions to match
# The robot is up once its state messages reach us within this of their stamps: all its
# nodes share one executor, which can start with a backlog of the start-up's messages
# (commands delivered 0.8 s late, and so rejected as stale, were measured without this).
READY_LATENCY_S = 0.05  # [s]
RECORD_DEPTH = 50  # messages a recording subscription holds while the executor is busy
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
# A plugin is up once it has published here (plugins without one are not waited for; the
# imu plugin's /imu is not watched: 400 messages/s for the one executor, and the gimbal
# reports on /gimbal_state whether it has IMU data).
READY_TOPICS: dict[str, tuple[str, str]] = {
    'chassis': ('/chassis_state', 'rm_msgs/msg/ChassisState'),
    'gimbal': ('/gimbal_state', 'rm_msgs/msg/GimbalState'),
    'shooter': ('/shooter_state', 'rm_msgs/msg/ShooterState'),
    'gpio': ('/gpio_state', 'rm_msgs/msg/GpioState'),
}


class ReplayError(RuntimeError):
    """The replay could not run as the scenario says (robot not ready, bag mismatch, stall)."""


@dataclass(frozen=True)
class Received:
    """One message the robot published, with when it arrived."""

    t: float  # [s] replay clock (sim time since playback start)
    wall: float  # [s] wall clock since playback start
    stamp_ns: int  # ROS time of arrival [ns]
    msg: Any


@dataclass(frozen=True)
class Sent:
    """One command as published (with its rewritten stamps)."""

    t: float  # [s] replay clock
    wall: float  # [s] wall clock since playback start
    bag_t: float  # [s] its time in the bag
    stamp_ns: int  # ROS time it was published with [ns]
    msg: Any
    refresh: bool = False  # sent again to keep the stream live (module docstring)


@dataclass(frozen=True)
class BodySample:
    """Sim ground truth: chassis pose in the world, its twist, the gimbal joints."""

    t: float  # [s] replay clock
    wall: float  # [s] wall clock since playback start
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
    played: int  # messages of the bag published (refreshes not counted)
    duration_s: float  # replay clock at the end of the recording [s]
    wall_s: float  # wall time from playback start to the end of the recording [s]
    sim_overruns: int  # times the simulator let its time slip (CPU starved)
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
        """The last command published on topic (a bag message or a refresh of one)."""
        return self.sent[topic][-1]

    @property
    def refreshed(self) -> int:
        """Commands sent again to keep a stream live while the sim lagged."""
        return sum(1 for log in self.sent.values() for s in log if s.refresh)

    @property
    def stalls(self) -> list[float]:
        """Wall-clock gaps between the harness's own samples longer than 0.1 s [s].

        The sampler wakes every 10 ms; longer gaps mean this process got no CPU (or no
        GIL) for that long, and so, most likely, did the plugins and the bridge.
        """
        return [b.wall - a.wall for a, b in itertools.pairwise(self.body) if b.wall - a.wall > 0.1]

    def summary(self) -> str:
        """One line: played, durations, sim slip, stalls."""
        counts = ', '.join(f'{t} {len(r)}' for t, r in self.received.items() if r)
        stalls = self.stalls
        worst = f', longest {max(stalls):.2f} s' if stalls else ''
        return (
            f'{self.scenario.name}: played {self.played} messages (+{self.refreshed} '
            f'refreshed); {self.duration_s:.2f} s sim in {self.wall_s:.2f} s wall '
            f'({self.sim_overruns} sim overruns; {len(stalls)} stalls > 0.1 s{worst}); '
            f'received {counts}'
        )


def bag_path(scenario: Scenario) -> Path:
    """The committed bag of a scenario."""
    return DATA_DIR / scenario.name


class _Clock:
    """The replay clock (sim time since start) and the wall clock since start."""

    def __init__(self, world: Any) -> None:
        self._world = world
        self._sim0_ns = world.time_ns
        self._wall0 = time.monotonic()

    def sim_elapsed_ns(self) -> int:
        return self._world.time_ns - self._sim0_ns

    def t(self) -> float:
        return self.sim_elapsed_ns() * 1e-9

    def wall(self) -> float:
        return time.monotonic() - self._wall0


class _Pacer:
    """Holds each message back until the simulated world has reached its bag time.

    play() publishes in the bag's order; the pacer knows that order (read from the same
    bag beforehand) and checks that each publish is the one it expects.
    """

    def __init__(self, schedule: list[tuple[str, int]], clock: _Clock, stop: threading.Event):
        self._schedule = schedule
        self._index = 0
        self._clock = clock
        self._stop = stop

    def wait_turn(self, topic: str) -> int | None:
        """Wait for the next message's time on the replay clock; return its offset [ns].

        Returns None if the replay was stopped meanwhile.
        """
        if self._index >= len(self._schedule):
            raise ReplayError(f'play() published more messages than the bag has ({topic})')
        expected, offset_ns = self._schedule[self._index]
        if expected != topic:
            raise ReplayError(f'message {self._index}: play() sent {topic}, the bag has {expected}')
        self._index += 1
        while not self._stop.is_set():
            remaining_ns = offset_ns - self._clock.sim_elapsed_ns()
            if remaining_ns <= 0:
                return offset_ns
            # The sim never runs ahead of the wall clock, so this never oversleeps.
            self._stop.wait(max(remaining_ns * 1e-9, 0.0005))
        return None


class _CommandPublisher:
    """What play() publishes through: paced by the sim, restamped, kept live, logged."""

    def __init__(self, topic, publisher, msg_class, offsets_ns, pacer, clock, ros_clock, log):
        self._topic = topic
        self._publisher = publisher
        self._msg_class = msg_class
        self._offsets_ns = offsets_ns  # bag offsets of this topic's messages
        steps = [b - a for a, b in itertools.pairwise(offsets_ns) if b > a]
        self._period_ns = min(steps) if steps else None
        self._pacer = pacer
        self._clock = clock
        self._ros_clock = ros_clock
        self._log = log
        self._lock = threading.Lock()
        self._count = 0
        self._last: tuple[bytes, int] | None = None  # raw CDR and bag offset [ns]
        self._last_wall = 0.0
        self._continues = False

    def publish(self, raw: bytes) -> None:
        offset_ns = self._pacer.wait_turn(self._topic)
        if offset_ns is None:
            return
        with self._lock:
            index, self._count = self._count, self._count + 1
            following = self._offsets_ns[index + 1 : index + 2]
            self._continues = (
                bool(following)
                and self._period_ns is not None
                and (following[0] - offset_ns <= 1.5 * self._period_ns)
            )
            self._send(bytes(raw), offset_ns, refresh=False)

    def refresh(self) -> None:
        """Send the last message again if the stream continues and REFRESH_PERIODS passed."""
        with self._lock:
            if self._last is None or not self._continues:
                return
            if self._clock.wall() - self._last_wall < REFRESH_PERIODS * self._period_ns * 1e-9:
                return
            self._send(*self._last, refresh=True)

    def _send(self, raw: bytes, offset_ns: int, *, refresh: bool) -> None:
        from rclpy.serialization import deserialize_message

        msg = deserialize_message(raw, self._msg_class)
        now = self._ros_clock.now()
        for header in headers(msg):
            header.stamp = now.to_msg()
        self._publisher.publish(msg)
        self._last, self._last_wall = (raw, offset_ns), self._clock.wall()
        self._log.append(
            Sent(
                self._clock.t(),
                self._last_wall,
                offset_ns * 1e-9,
                now.nanoseconds,
                msg,
                refresh,
            )
        )


class _Faults:
    """Applies a scenario's faults at their bag times (called from the sampler)."""

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
        with self._world.lock:
            model = self._world.motor(motor).model
            return model.torque, model.velocity


def _sample_body(world: Any, clock: _Clock, ros_clock: Any) -> BodySample:
    with world.lock:
        b = world.body
        vx, vy, wz = b.twist
        values = (b.x, b.y, b.yaw, vx, vy, wz, b.gimbal_yaw, b.gimbal_pitch)
    return BodySample(clock.t(), clock.wall(), ros_clock.now().nanoseconds, *values)


class _Recorder:
    """Subscriptions on the robot's driver node that keep every output message."""

    def __init__(
        self, robot: Any, outputs: tuple[tuple[str, str], ...], watched: list[tuple[str, str]]
    ) -> None:
        """Record outputs (after start()); of watched topics only note the first message."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rm_bringup.cli.interfaces import get_message_class

        self._lock = threading.Lock()
        self._clock: _Clock | None = None
        self._ros_clock = robot.driver.get_clock()
        self.received: dict[str, list[Received]] = {topic: [] for topic, _ in outputs}
        self.first_seen: set[str] = set()
        self.latency_s: dict[str, float] = {}  # the latest message's receive time - stamp
        # Best effort matches every publisher (reliable or not); a bounded depth, so that
        # a busy executor drops old samples here rather than queueing work for later.
        qos = QoSProfile(depth=RECORD_DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._subscriptions = [
            robot.driver.create_subscription(
                get_message_class(msgtype), topic, self._callback(topic), qos
            )
            for topic, msgtype in (*outputs, *watched)
        ]

    def _callback(self, topic: str) -> Callable[[Any], None]:
        def store(msg: Any) -> None:
            stamp_ns = self._ros_clock.now().nanoseconds
            header = getattr(msg, 'header', None)
            with self._lock:
                self.first_seen.add(topic)
                if header is not None:
                    sent_ns = header.stamp.sec * 1_000_000_000 + header.stamp.nanosec
                    self.latency_s[topic] = (stamp_ns - sent_ns) * 1e-9
                if self._clock is not None and topic in self.received:
                    clock = self._clock
                    self.received[topic].append(Received(clock.t(), clock.wall(), stamp_ns, msg))

        return store

    def keeping_up(self, topics: list[str]) -> bool:
        """Whether every topic has arrived, its latest message within READY_LATENCY_S."""
        with self._lock:
            return all(self.latency_s.get(topic, math.inf) < READY_LATENCY_S for topic in topics)

    def start(self, clock: _Clock) -> None:
        """Record from now on."""
        with self._lock:
            self._clock = clock

    def stop(self) -> dict[str, list[Received]]:
        with self._lock:
            self._clock = None
            return {topic: list(samples) for topic, samples in self.received.items()}


def replay(
    scenario: Scenario,
    *,
    bag: Path | None = None,
    output: Path | None = None,
    record: tuple[str, ...] | None = None,
    timeout_factor: float = 6.0,
) -> ReplayResult:
    """Play a scenario's bag into a fresh SimRobot and record the outcome (module docstring).

    Args:
        scenario: what to build and do (robot, faults, tail).
        bag: the command bag (default: test/data/<scenario.name>).
        output: write commands, outputs and the sim body into a new bag here.
        record: the robot's output topics to record (OUTPUTS); default the scenario's.
        timeout_factor: give up when the replay takes this many times the scenario's
            length of wall time (a simulator that stopped).

    Raises:
        ReplayError: the robot did not come up, the bag and the schedule disagree, or
            the replay took too long.
    """
    from rm_bringup.cli.bag_io import open_bag, read_messages
    from rm_bringup.cli.bag_play import PlayOptions, play
    from rm_bringup.cli.interfaces import get_message_class
    from rm_bringup.cli.qos import offer_for_recorded
    from support.robot import SimRobot

    bag = bag_path(scenario) if bag is None else Path(bag)
    setup = scenario.robot
    with (
        SimRobot(setup.config, plugins=list(setup.plugins), overrides=setup.overrides) as robot,
        open_bag(bag) as reader,
    ):
        ready_topics = [READY_TOPICS[p] for p in setup.plugins if p in READY_TOPICS]
        ready = [topic for topic, _ in ready_topics]
        types = dict(OUTPUTS)
        topics = scenario.record if record is None else record
        unknown = sorted(set(topics) - set(types))
        if unknown:
            raise ReplayError(f'cannot record {unknown}: the outputs are {sorted(types)}')
        outputs = tuple((topic, types[topic]) for topic in topics)
        watched = [(t, msgtype) for t, msgtype in ready_topics if t not in topics]
        recorder = _Recorder(robot, outputs, watched)
        connections = list(reader.connections)
        publishers = {}
        for connection in connections:
            offered = list(connection.ext.offered_qos_profiles)
            publishers[connection.topic] = robot.driver.create_publisher(
                get_message_class(connection.msgtype),
                connection.topic,
                offer_for_recorded(offered),
            )
        # Matched both ways: our publisher sees the robot's subscription, and that
        # subscription sees our publisher. A reliable reader drops what a writer sends
        # before the reader has matched it, and under CPU starvation the two sides of
        # discovery can be a second apart (the first commands were lost that way).
        readers = [s for s in robot.host.subscriptions if s.topic_name in publishers]

        def unmatched() -> list[str]:
            return sorted(
                topic
                for topic, publisher in publishers.items()
                if publisher.get_subscription_count() == 0
                or not any(s.get_publisher_count() > 0 for s in readers if s.topic_name == topic)
            )

        if not robot.wait_until(
            lambda: recorder.keeping_up(ready) and not unmatched(), READY_TIMEOUT_S
        ):
            missing = sorted(set(ready) - recorder.first_seen)
            raise ReplayError(
                f'{scenario.name}: robot not ready after {READY_TIMEOUT_S} s '
                f'(no message on {missing}, latency {recorder.latency_s} s, '
                f'not matched both ways: {unmatched()})'
            )

        start_ns = reader.start_time
        schedule = [
            (c.topic, stamp - start_ns)
            for c, stamp, _ in read_messages(reader, bag, connections, start=start_ns)
        ]
        stop = threading.Event()
        world = robot.world
        clock = _Clock(world)
        overruns0 = world.overruns
        ros_clock = robot.driver.get_clock()
        pacer = _Pacer(schedule, clock, stop)
        sent: dict[str, list[Sent]] = {topic: [] for topic in publishers}
        adapters = {
            topic: _CommandPublisher(
                topic,
                publisher,
                get_message_class(next(c.msgtype for c in connections if c.topic == topic)),
                [offset for t, offset in schedule if t == topic],
                pacer,
                clock,
                ros_clock,
                sent[topic],
            )
            for topic, publisher in publishers.items()
        }
        faults = _Faults(world, scenario.faults)
        body: list[BodySample] = []
        done = threading.Event()
        wall_limit = timeout_factor * (scenario.end_s + scenario.tail_s) + READY_TIMEOUT_S
        timed_out = threading.Event()

        sampler_errors: list[BaseException] = []

        def sample() -> None:
            try:
                while not done.is_set():
                    t = clock.t()
                    body.append(_sample_body(world, clock, ros_clock))
                    faults.update(t)
                    for adapter in adapters.values():
                        adapter.refresh()
                    if clock.wall() > wall_limit:
                        timed_out.set()
                        break
                    done.wait(SAMPLE_PERIOD_S)
            except BaseException as err:  # ends the replay; raised again below
                sampler_errors.append(err)
            if not done.is_set():
                stop.set()

        recorder.start(clock)
        sampler = threading.Thread(target=sample, name=f'replay-{scenario.name}', daemon=True)
        sampler.start()
        try:
            played = play(reader, bag, connections, adapters, options=PlayOptions(), stop=stop)
            end_ns = round((scenario.end_s + scenario.tail_s) * 1e9)
            while not stop.is_set() and clock.sim_elapsed_ns() < end_ns:
                stop.wait(SAMPLE_PERIOD_S)
        finally:
            done.set()
            sampler.join(timeout=5.0)
            received = recorder.stop()
        if sampler_errors:
            raise ReplayError(f'{scenario.name}: the sampler failed') from sampler_errors[0]
        if timed_out.is_set():
            raise ReplayError(
                f'{scenario.name}: replay still running after {wall_limit:.0f} s wall '
                f'(replay clock at {clock.t():.2f} s)'
            )
        result = ReplayResult(
            scenario=scenario,
            received=received,
            sent=sent,
            body=body,
            faults=faults.records,
            played=sum(1 for log in sent.values() for s in log if not s.refresh),
            duration_s=clock.t(),
            wall_s=clock.wall(),
            sim_overruns=world.overruns - overruns0,
            parameters={'can_bridge': robot.bridge_parameters, 'rm_robot': robot.host_parameters},
        )
        if played != result.played:
            raise ReplayError(f'play() reported {played} messages, {result.played} went out')
    if output is not None:
        result.output = write_output_bag(result, Path(output))
    return result


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
