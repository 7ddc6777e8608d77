"""The replay scenarios: timed command streams, the robot they drive, and injected faults.

A scenario is what an operator (or a planner) did, written down as data:

- ``commands``: streams of one message on one topic at ``rate_hz`` over ``[start_s, end_s)``
  of bag time, the fields given as ``rmcli topic pub`` / ``ros2 topic pub`` would take
  them (constant names allowed: ``{'mode': 'raw'}``). scripts/make_scenario_bags.py
  writes them into test/data/<name>/ as a rosbag2 (MCAP) bag: one message every
  1/rate_hz, header stamps equal to the time since the bag start (the first message is
  at 0 s), each topic offset by a millisecond from the previous one like independent
  publishers. The bags hold commands only.
- ``robot``: the robot to replay into (in lockstep): robot config, plugins, parameter overrides.
- ``faults``: what the harness does to the simulated world during the replay, at bag time
  (the fault schedule lives here, not in the bag, since no ROS message carries it).
- ``tail_s``: how long the harness keeps recording after the last command.
- ``record``: the robot's output topics the harness records (the sim's ground truth is
  always sampled); only what the tests need.
- ``remaps``: ``FROM:=TO`` topic renames the harness plays the bag with, as
  ``rmcli bag play --remap`` takes them (a teleop bag's /cmd_vel played as /vel_cmd).

Simulated loads: standard_sim.yaml gives the turret, barrel, friction wheels and trigger
their loads but leaves the wheels with nothing but their rotors, which makes the wheel
loops the robot config was tuned for (wheels carrying a 16 kg robot) far too fast on the
sim: they oscillate. ``SIM_LOADS`` gives the wheels the robot's mass as test_chassis.py
does; it is physics of the simulated robot, not tuning (and belongs in the overlay).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

DATA_DIR = Path(__file__).resolve().parents[1] / 'data'  # test/data/<scenario>/: the bags
RATE_HZ = 50.0  # [Hz] command rate of a live commander (RoboMaster clients send 50-100 Hz)
TOPIC_OFFSET_NS = 1_000_000  # [ns] between the streams of different topics

OUTPUT_TOPICS = ('/odom', '/chassis_state', '/gimbal_state', '/shooter_state', '/actuator_states')

CHASSIS_CMD = ('/chassis_cmd', 'rm_msgs/msg/ChassisCmd')
VEL_CMD = ('/vel_cmd', 'geometry_msgs/msg/Twist')
GIMBAL_CMD = ('/gimbal_cmd', 'rm_msgs/msg/GimbalCmd')
SHOOT_CMD = ('/shoot_cmd', 'rm_msgs/msg/ShootCmd')

WHEELS = ('wheel_fl', 'wheel_fr', 'wheel_rl', 'wheel_rr')
ROBOT_MASS = 16.0  # [kg]
WHEEL_RADIUS = 0.0763  # [m] = standard.yaml chassis.wheel_radius
# The sim's chassis body is kinematic: the robot's mass sits in the wheel motors, a
# quarter at each rim: m / 4 * r^2 = 16 / 4 * 0.0763^2 = 0.0233 kg*m^2.
WHEEL_LOAD_INERTIA = ROBOT_MASS / 4.0 * WHEEL_RADIUS**2

SIM_LOADS: dict[str, dict[str, float]] = {
    'chassis': {f'joints.{w}.sim.load_inertia': WHEEL_LOAD_INERTIA for w in WHEELS},
}


def robot_overrides(bridge: Mapping[str, Any] = ()) -> dict[str, dict[str, Any]]:
    """LockstepRobot overrides: the bridge's (simulated loads); the plugins as configured."""
    return {'can_bridge': dict(bridge), 'rm_robot': {}}


@dataclass(frozen=True)
class Command:
    """One message published on topic every 1/rate_hz over [start_s, end_s) of bag time."""

    topic: str
    msgtype: str
    fields: Mapping[str, Any]
    start_s: float
    end_s: float
    rate_hz: float = RATE_HZ


@dataclass(frozen=True)
class Jam:
    """A ball that wedges in a mechanism: from ``at_s`` [s of bag time] on, the next push.

    From ``at_s`` the jam is armed. The next time ``motor`` drives forward -- moving at
    ``speed`` [rad/s] or more while pushing with ``torque`` [N*m] or more (the sim's
    output shaft; positive = the feed direction) -- the ball wedges: the motor locks. It
    comes free once the motor has pushed back with at least ``torque`` for ``free_s``
    [s], as a jammed trigger is freed by reversing. Armed rather than locked at once,
    and freed by a sustained reverse only: a lock at an arbitrary instant can catch the
    trigger braking past the end of a step, and a lock's recoil pulls back for a few ms,
    neither of which a ball does.
    """

    motor: str
    at_s: float
    torque: float = 0.5
    speed: float = 1.0
    free_s: float = 0.05


@dataclass(frozen=True)
class Robot:
    """The simulated robot a scenario drives (support.lockstep.LockstepRobot arguments)."""

    plugins: tuple[str, ...]
    overrides: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    config: str = 'standard'


@dataclass(frozen=True)
class Scenario:
    """Commands, the robot they drive, faults, and the recording after the last command."""

    name: str
    description: str
    robot: Robot
    commands: tuple[Command, ...]
    faults: tuple[Jam, ...] = ()
    tail_s: float = 1.0
    record: tuple[str, ...] = OUTPUT_TOPICS
    remaps: tuple[str, ...] = ()

    @property
    def end_s(self) -> float:
        """End of the last command stream [s of bag time]."""
        return max(c.end_s for c in self.commands)

    @property
    def topics(self) -> list[tuple[str, str]]:
        """(topic, msgtype) of every command stream, in order of first appearance."""
        seen: dict[str, str] = {}
        for command in self.commands:
            if seen.setdefault(command.topic, command.msgtype) != command.msgtype:
                raise ValueError(f'{self.name}: {command.topic} has two message types')
        return list(seen.items())

    def timeline(self) -> Iterator[tuple[int, Command]]:
        """(bag time [ns], command) of every message, in time order.

        Each topic streams on one grid, as a live commander does: a message every 1/rate
        from its first command's start, offset by TOPIC_OFFSET_NS times the topic's index
        in ``topics``; a message carries the command whose [start, end) holds its time,
        and none is sent where no command does (a dropout). Integer nanoseconds, no drift.

        Raises:
            ValueError: two commands of a topic overlap or differ in rate.
        """
        events = []
        for index, (topic, _) in enumerate(self.topics):
            spans = sorted((c for c in self.commands if c.topic == topic), key=lambda c: c.start_s)
            if len({c.rate_hz for c in spans}) != 1:
                raise ValueError(f'{self.name}: the commands on {topic} differ in rate')
            for a, b in itertools.pairwise(spans):
                if b.start_s < a.end_s:
                    raise ValueError(f'{self.name}: commands on {topic} overlap at {b.start_s:g} s')
            period_ns = round(1e9 / spans[0].rate_hz)
            origin_ns = round(spans[0].start_s * 1e9)
            for command in spans:
                start_ns, end_ns = round(command.start_s * 1e9), round(command.end_s * 1e9)
                # The first grid point at or after the command's start.
                first = origin_ns + _ceil_div(start_ns - origin_ns, period_ns) * period_ns
                events.extend(
                    (t + index * TOPIC_OFFSET_NS, command) for t in range(first, end_ns, period_ns)
                )
        events.sort(key=lambda event: event[0])
        return iter(events)

    def messages(self) -> Iterator[tuple[int, str, str, Any]]:
        """(bag time [ns], topic, msgtype, rclpy message) of every message, in time order.

        Every std_msgs/Header in the message (``header``, ``target.header``) is stamped
        with the bag time.
        """
        from builtin_interfaces.msg import Time
        from rm_bringup.cli.interfaces import get_message_class
        from rm_bringup.cli.message_yaml import fill_message

        for t_ns, command in self.timeline():
            msg = get_message_class(command.msgtype)()
            fill_message(msg, command.fields)
            stamp = Time(sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)
            for header in headers(msg):
                header.stamp = stamp
            yield t_ns, command.topic, command.msgtype, msg


def _ceil_div(a: int, b: int) -> int:
    return -(-a // b)


def headers(msg: Any) -> Iterator[Any]:
    """Every std_msgs/Header inside a message (depth first), the message's own first."""
    for name, typename in msg.get_fields_and_field_types().items():
        value = getattr(msg, name)
        if typename == 'std_msgs/Header':
            yield value
        elif '/' in typename and not typename.startswith(('sequence<', 'builtin_interfaces/')):
            if hasattr(value, 'get_fields_and_field_types'):
                yield from headers(value)


def _streams(topic_type: tuple[str, str], *spans: tuple[float, float, Mapping[str, Any]]):
    """Commands on one topic: (start_s, end_s, fields) each."""
    topic, msgtype = topic_type
    return tuple(Command(topic, msgtype, fields, start, end) for start, end, fields in spans)


def _twist(vx: float = 0.0, vy: float = 0.0, wz: float = 0.0) -> dict[str, Any]:
    return {'linear': {'x': vx, 'y': vy}, 'angular': {'z': wz}}


# -- 1. a square in RAW -------------------------------------------------------------------------
# 1 m sides at 1 m/s: each leg is commanded for 1 s (the ramps lose a little on the way up
# and win a little back while braking), with 0.5 s of zero velocity between legs so that
# they do not blend. Forward, left, back, right: the robot ends where it started, heading
# unchanged.
SQUARE_SPEED = 1.0  # [m/s]
SQUARE_LEG_S = 1.0  # [s]
SQUARE_PAUSE_S = 0.5  # [s]
SQUARE_START_S = 0.5  # [s] standing still in RAW first


def _square_legs() -> tuple[tuple[float, float, dict[str, Any]], ...]:
    directions = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]
    spans = [(0.0, SQUARE_START_S, _twist())]
    t = SQUARE_START_S
    for dx, dy in directions:
        spans.append((t, t + SQUARE_LEG_S, _twist(SQUARE_SPEED * dx, SQUARE_SPEED * dy)))
        t += SQUARE_LEG_S
        spans.append((t, t + SQUARE_PAUSE_S, _twist()))
        t += SQUARE_PAUSE_S
    return tuple(spans)


SQUARE_END_S = SQUARE_START_S + 4 * (SQUARE_LEG_S + SQUARE_PAUSE_S)  # 6.5 s

SQUARE = Scenario(
    name='square',
    description='RAW: 1 m forward, left, back and right at 1 m/s, back at the start',
    robot=Robot(
        plugins=('chassis',), overrides=robot_overrides(SIM_LOADS['chassis'])
    ),
    commands=(
        *_streams(CHASSIS_CMD, (0.0, SQUARE_END_S, {'mode': 'raw'})),
        *_streams(VEL_CMD, *_square_legs()),
    ),
    tail_s=1.0,
    record=('/odom', '/chassis_state'),
)

# -- 2. GYRO with the gimbal tracking a world point -----------------------------------------------
# The gimbal tracks a point 3.6 m away in odom, level with its pivot (0.35 m above
# base_link); after 2.5 s standing still (the gimbal turns 0.59 rad onto the point and
# lifts the barrel that drooped while limp; with standard.yaml's yaw loops the turn
# overshoots by ~0.4 rad and rings for 1.5-1.8 s) the chassis spins in GYRO for 4.5 s,
# then stops (RAW, zero velocity).
TRACK_TARGET = (3.0, 2.0, 0.35)  # [m] in odom
GYRO_START_S = 2.5
GYRO_END_S = 7.0
GYRO_STOP_END_S = 8.0
# The sim's kinematic body carries the robot's mass as wheel inertia, which makes turning
# ~4x as costly as on the real robot; 500 W keeps the power limit out of the way.
GYRO_POWER_LIMIT = 500.0  # [W]

# The simulated Hi220 at 200 frames/s instead of 400 (as test_gimbal.py runs it): this
# replay runs three plugins, the 1 kHz sim and bridge and the IMU stream in one process,
# and every IMU frame is read, parsed and delivered to two plugins by the one executor.
GYRO_IMU_RATE = 200.0  # [Hz]

GYRO_TRACK = Scenario(
    name='gyro_track',
    description='GYRO spin in place for 4.5 s, gimbal TRACK on a point in odom',
    robot=Robot(
        plugins=('imu', 'chassis', 'gimbal'),
        overrides=robot_overrides({**SIM_LOADS['chassis'], 'sim.imu.rate_hz': GYRO_IMU_RATE}),
    ),
    commands=(
        *_streams(
            GIMBAL_CMD,
            (
                0.0,
                GYRO_STOP_END_S,
                {
                    'mode': 'track',
                    'target': {
                        'header': {'frame_id': 'odom'},
                        'point': dict(zip('xyz', TRACK_TARGET, strict=True)),
                    },
                },
            ),
        ),
        *_streams(
            CHASSIS_CMD,
            (0.0, GYRO_START_S, {'mode': 'raw', 'power_limit': GYRO_POWER_LIMIT}),
            (GYRO_START_S, GYRO_END_S, {'mode': 'gyro', 'power_limit': GYRO_POWER_LIMIT}),
            (GYRO_END_S, GYRO_STOP_END_S, {'mode': 'raw', 'power_limit': GYRO_POWER_LIMIT}),
        ),
        *_streams(VEL_CMD, (0.0, GYRO_STOP_END_S, _twist())),
    ),
    tail_s=0.5,
    record=('/gimbal_state',),
)

# -- 3. a five-shot burst with a jam --------------------------------------------------------------
# READY (friction wheels up, a ball fed), then PUSH 5 shots at 5 Hz held until 4.5 s, then
# PASSIVE. From 0.5 s into the burst (after 2-3 shots) the next push of the trigger jams;
# the jam frees when the trigger reverses (BLOCK), so the burst completes with one jam.
BURST_START_S = 1.5
BURST_END_S = 4.5
BURST_PASSIVE_END_S = 5.0
BURST_SHOTS = 5
JAM_AT_S = BURST_START_S + 0.5

BURST_JAM = Scenario(
    name='burst_jam',
    description='READY, PUSH 5 shots at 5 Hz with a trigger jam 0.5 s in, then PASSIVE',
    robot=Robot(
        plugins=('gpio', 'shooter'),
        overrides=robot_overrides(),
    ),
    commands=_streams(
        SHOOT_CMD,
        (0.0, BURST_START_S, {'mode': 'ready', 'speed': 15.0}),
        (
            BURST_START_S,
            BURST_END_S,
            {'mode': 'push', 'speed': 15.0, 'hz': 5.0, 'num': BURST_SHOTS, 'burst_id': 1},
        ),
        (BURST_END_S, BURST_PASSIVE_END_S, {'mode': 'passive'}),
    ),
    faults=(Jam('trigger', JAM_AT_S),),
    tail_s=0.5,
    record=('/shooter_state', '/actuator_states'),
)

# -- 4. command dropout while driving -------------------------------------------------------------
# RAW at 1 m/s forward; every command stops at 2 s (the commander died). The chassis goes
# PASSIVE (limp) after its command_timeout and coasts to a stop on the motors' friction
# (~3 s from 1 m/s on the sim), which the 4 s of recording after the bag cover.
DROPOUT_AT_S = 2.0

DROPOUT = Scenario(
    name='dropout',
    description='RAW 1 m/s forward; all commands stop at 2 s',
    robot=Robot(
        plugins=('chassis',),
        overrides=robot_overrides(SIM_LOADS['chassis']),
    ),
    commands=(
        *_streams(CHASSIS_CMD, (0.0, DROPOUT_AT_S, {'mode': 'raw'})),
        *_streams(VEL_CMD, (0.0, DROPOUT_AT_S, _twist(vx=1.0))),
    ),
    tail_s=4.0,
    record=('/chassis_state', '/actuator_states'),
)

# -- 5. a teleop session ------------------------------------------------------------------------
# What `ros2 bag record` keeps of an operator driving with teleop_twist_keyboard: its Twist
# on /cmd_vel (0.5 m/s, 1 rad/s: the tool's defaults; a message per key repeat, ~10 Hz) and
# the chassis mode from `rmcli topic pub -r 20 /chassis_cmd ...`. Played with
# ``--remap /cmd_vel:=/vel_cmd``. Keys, as (start, end, key): i forward, u forward-left,
# j left in place, k stop.
CMD_VEL = ('/cmd_vel', 'geometry_msgs/msg/Twist')
TELEOP_RATE_HZ = 10.0  # [Hz] key repeat
TELEOP_MODE_HZ = 20.0  # [Hz] rmcli topic pub -r 20
TELEOP_KEYS: tuple[tuple[float, float, tuple[float, float]], ...] = (  # (vx [m/s], wz [rad/s])
    (1.0, 3.0, (0.5, 0.0)),  # i
    (3.0, 4.5, (0.5, 1.0)),  # u
    (4.5, 6.0, (0.5, 0.0)),  # i
    (6.0, 6.5, (0.0, 0.0)),  # k
    (6.5, 8.0, (0.0, 1.0)),  # j
    (8.0, 8.5, (0.0, 0.0)),  # k
)
TELEOP_END_S = 9.0

TELEOP = Scenario(
    name='teleop',
    description='teleop_twist_keyboard on /cmd_vel (played as /vel_cmd), chassis RAW',
    robot=Robot(plugins=('chassis',), overrides=robot_overrides(SIM_LOADS['chassis'])),
    commands=(
        Command(CHASSIS_CMD[0], CHASSIS_CMD[1], {'mode': 'raw'}, 0.0, TELEOP_END_S,
                TELEOP_MODE_HZ),
        *(Command(CMD_VEL[0], CMD_VEL[1], _twist(vx=vx, wz=wz), start, end, TELEOP_RATE_HZ)
          for start, end, (vx, wz) in TELEOP_KEYS),
    ),
    tail_s=1.0,
    record=('/odom',),
    remaps=('/cmd_vel:=/vel_cmd',),
)

SCENARIOS: dict[str, Scenario] = {
    s.name: s for s in (SQUARE, GYRO_TRACK, BURST_JAM, DROPOUT, TELEOP)
}

# The gimbal tracks a point at this bearing from the start position [rad].
TRACK_BEARING = math.atan2(TRACK_TARGET[1], TRACK_TARGET[0])
