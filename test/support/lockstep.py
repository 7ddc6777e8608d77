"""LockstepRobot: the whole robot — loop, plugins and simulator — stepped tick by tick.

    with LockstepRobot() as robot:
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=50)
        robot.publish('/vel_cmd', Twist(linear=Vector3(x=1.0)), rate_hz=50)
        robot.run(3.0)
        assert robot.world.body.x > 2.5

The robot comes from the robot config and its simulation overlay, as `bringup --sim`
loads them (support.robot.robot_parameters), with the simulator stepped
(``sim.timing: stepped``) and the plugins on simulated ROS time (``use_sim_time``, the
clock set by the harness). Each tick the simulator moves one period, then one loop tick
runs at the new time (feedback, due plugins, update, pack, send: ``CanBridgeNode.step``).
Commands are handed to the plugins through the same callbacks their subscriptions run
(``RobotHost.inject``), stamped on the simulated clock; what a plugin publishes reaches
the plugins subscribed to it at once (outbox loopback); the simulated Hi220's frames
are decoded as the Hi220 plugin decodes them and handed to /imu's subscribers, the
simulated referee's frames (when the config has one) as the Referee plugin decodes them and
handed to the subscribers of its topics (and what the plugins publish on
referee/interaction paced as the Referee plugin paces it, then handed to the simulated
referee's client; the bridge's /diagnostics at its rate to the plugins that listen), and
the simulated DR16's and image link's frames
decoded and handed to the manual-control plugin as its readers would (rm_manual's plugin,
run inside rm_robot here so it steps with the loop). No
executor spins, nothing waits on DDS or a terminal: the same inputs give the same numbers
on every run, whatever the machine's load.
"""

from __future__ import annotations

import copy
import os
import shutil
import tempfile
from collections.abc import Callable, Mapping
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.time import Time
from rm_base.bridge import CanBridgeNode
from rm_base.bridge.messages import state_msgs
from rm_base.hardware.protocols import dbus
from rm_base.hardware.protocols import referee as ref
from rm_base.hardware.protocols.hipnuc import decode_frame, decode_payload
from rm_base.host.node import RobotHost
from rm_base.sim import SimImageLink, SimImu, SimRemote
from rm_plugins.imu.conversion import Mounting, reading_from_sample
from rm_plugins.imu.message import imu_message
from rm_plugins.manual.driver import Keyboard
from rm_plugins.referee.interaction import InteractionLink
from rm_plugins.referee.messages import TOPICS as REFEREE_TOPICS

from support.robot import _parameter, robot_parameters

#: Simulated ROS time at the world's time 0 [ns] (any fixed, positive value).
BASE_NS = 1_700_000_000 * 1_000_000_000

#: Covariances of the injected /imu (the plugins read no covariance).
_IMU_COVARIANCE = (0.0,) * 9


class LockstepRobot:
    """The robot of one config, stepped on a simulated clock (see the module docstring).

    Args:
        config: robot config name in rm_bringup/config.
        plugins: plugin instances to run. ``imu`` (the Hi220) and ``referee`` are played
            by the harness: it decodes the simulated IMU's (referee's) frames as the plugin
            does and hands them to the subscribers of its topics; without it nothing is
            published on them. ``manual`` (rm_manual's plugin) runs in rm_robot, fed the
            simulated DR16's and image link's frames.
        overrides: ``{'can_bridge' | 'rm_robot': {flat parameter: value}}`` applied last.
    """

    def __init__(
        self,
        config: str = 'standard',
        *,
        plugins: tuple[str, ...] = (
            'imu', 'gpio', 'referee', 'manual', 'chassis', 'gimbal', 'shooter'
        ),
        overrides: Mapping[str, Mapping[str, Any]] | None = None,
    ) -> None:
        self._tmp = tempfile.mkdtemp(prefix='rm_lockstep_')
        loaded = [p for p in plugins if p not in ('imu', 'referee')]
        self._played = frozenset(plugins) & {'imu', 'referee'}
        bridge, host = robot_parameters(config, self._tmp, loaded, overrides)
        bridge['sim.timing'] = 'stepped'
        host['use_sim_time'] = True
        if 'manual' in plugins:
            # Its DR16 frames come from the harness; its reader holds a port that never
            # closes (a pty that stays silent would be reopened every silence_reopen).
            host['manual.dr16.port'] = 'loop://'
            host['manual.dr16.silence_reopen'] = 0.0
            if host.get('manual.image_link.port'):
                host['manual.image_link.port'] = 'loop://'
                host['manual.image_link.silence_reopen'] = 0.0
        self.bridge_parameters, self.host_parameters = bridge, host
        self._imu_topic = host.get('imu.topic', 'imu')
        self._imu_frame_id = host.get('imu.frame_id', 'gimbal_imu')
        self._mounting = Mounting(tuple(host.get('imu.mount_rpy', (0.0, 0.0, 0.0))))
        # topic: (message or factory, period [ticks], next tick, age of its stamps [s])
        self._streams: dict[str, tuple[Any, int, int, float]] = {}
        self._latest: dict[str, Any] = {}
        self._history: dict[str, list[Any]] = {}
        self._tick_hooks: list[Callable[[], object]] = []
        self._bridge_topics: set[str] = set()
        self._driven: dict[str, Mapping[str, float]] = {}
        self._state_every = round(1e9 / float(bridge.get('publish_rate', 200.0)))
        self._diagnostics_every = round(1e9 / float(bridge.get('diagnostics_rate', 1.0)))
        self.ticks = 0
        self.context = Context()
        rclpy.init(context=self.context, domain_id=int(os.environ['ROS_DOMAIN_ID']))
        self.bridge: CanBridgeNode | None = None
        self.host: RobotHost | None = None
        try:
            self.bridge = CanBridgeNode(
                context=self.context,
                parameter_overrides=[_parameter(k, v) for k, v in bridge.items()],
            )
            self.world = self.bridge.sim_world
            self.world.serial_sink = self._on_serial_frame
            self.host = RobotHost(
                hardware=self.bridge.hardware,
                take_from_dds=False,
                context=self.context,
                parameter_overrides=[_parameter(k, v) for k, v in host.items()],
            )
            self._clock = self.host.get_clock()
            # The referee plugin's way out, played too: what the plugins publish on
            # referee/interaction, paced as the plugin paces it, reaches rm_sim's referee.
            self.interaction = InteractionLink()
            if 'referee' in self._played:
                self.host.add_local_handler('referee/interaction', self._on_interaction)
            self._manual = self.host.plugin('manual') if 'manual' in plugins else None
            self._set_clock(self.world.time_ns)
        except BaseException:
            self.close()
            raise

    # -- life cycle -------------------------------------------------------------------------
    def close(self) -> None:
        """Disable the plugins (zero output), shut the bridge down, free everything."""
        if self.host is not None:
            self.host.destroy_node()
            self.host = None
        if self.bridge is not None:
            self.bridge.destroy_node()
            self.bridge = None
        self.context.try_shutdown()
        shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self) -> LockstepRobot:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- time -------------------------------------------------------------------------------
    @property
    def now_ns(self) -> int:
        """The simulated ROS time [ns]."""
        return BASE_NS + self.world.time_ns

    @property
    def t(self) -> float:
        """Simulated time since start [s]."""
        return self.world.time_ns / 1e9

    def _set_clock(self, world_ns: int) -> None:
        self._clock.set_ros_time_override(Time(nanoseconds=BASE_NS + world_ns))

    def step(self, ticks: int = 1) -> None:
        """Advance the whole robot by ticks loop periods (commands streamed as set up)."""
        period = self.world.period_ns
        for _ in range(ticks):
            self._set_clock(self.world.time_ns + period)
            for topic, (msg, every, next_tick, age_s) in list(self._streams.items()):
                if self.ticks >= next_tick:
                    self._streams[topic] = (msg, every, next_tick + every, age_s)
                    self._inject(topic, msg() if callable(msg) else msg, age_s)
            for joint, command in self._driven.items():
                self.bridge.hardware.set_command(joint, **command)
            self.bridge.step(1)
            self._relay_interaction()
            if self.world.time_ns % self._diagnostics_every == 0:
                # the bridge's /diagnostics, at its rate, to the plugins that listen
                self.host.inject('/diagnostics', self.bridge.diagnostics_message())
            self.ticks += 1
            for hook in self._tick_hooks:
                hook()

    def wait_until(self, predicate: Callable[[], Any], timeout: float) -> bool:
        """Step until predicate() is true, for at most timeout [s] of simulated time."""
        for _ in range(round(timeout * 1e9 / self.world.period_ns)):
            if predicate():
                return True
            self.step()
        return bool(predicate())

    def on_tick(self, hook: Callable[[], object]) -> None:
        """Call hook() after every tick from now on."""
        self._tick_hooks.append(hook)

    def run(self, seconds: float, every: Callable[[], object] | None = None) -> None:
        """Step for seconds of simulated time, calling every() after each tick."""
        for _ in range(round(seconds * 1e9 / self.world.period_ns)):
            self.step()
            if every is not None:
                every()

    # -- commands ---------------------------------------------------------------------------
    def publish(
        self, topic: str, msg: Any, *, rate_hz: float | None = None, age_s: float = 0.0
    ) -> None:
        """Hand msg to its subscribers now; with rate_hz, from the next tick every 1/rate_hz.

        msg may be a function that makes the message (called each time). A message with a
        header is stamped on the simulated clock each time, as a live commander does,
        age_s [s] in the past (a stale command: > its timeout).
        """
        every = 0 if rate_hz is None else round(1e9 / rate_hz / self.world.period_ns)
        if every:
            self._streams[topic] = (msg, every, self.ticks, age_s)
        else:
            self._streams.pop(topic, None)
            self._set_clock(self.world.time_ns)
            self._inject(topic, msg() if callable(msg) else msg, age_s)

    def stop_publishing(self, topic: str) -> None:
        """Stop a stream started by publish(..., rate_hz=...)."""
        self._streams.pop(topic, None)

    def _inject(self, topic: str, msg: Any, age_s: float = 0.0) -> None:
        if hasattr(msg, 'header'):  # the caller's message too, as a publisher stamps it
            stamp_ns = self._clock.now().nanoseconds - round(age_s * 1e9)
            msg.header.stamp = Time(nanoseconds=stamp_ns).to_msg()
        msg = copy.deepcopy(msg)  # each delivery a message of its own, as from DDS
        if self.host.inject(topic, msg) == 0:
            raise LookupError(f'no plugin subscribes {topic}')

    def _on_serial_frame(self, device: Any, frame: bytes) -> None:
        if isinstance(device, SimImu):
            if 'imu' in self._played:
                self._on_imu_frame(frame)
        elif isinstance(device, SimRemote):
            if self._manual is not None:
                self._manual.on_remote_frame(dbus.decode(frame), self._clock.now().nanoseconds)
        elif isinstance(device, SimImageLink):
            if self._manual is not None:
                k = ref.StatusDecoder(ref.ProtocolVersion.V2025).decode(ref.decode_frame(frame))
                self._manual.on_keyboard(
                    Keyboard(k.mouse_x, k.mouse_y, k.left, k.right, k.keys),
                    self._clock.now().nanoseconds,
                )
        elif 'referee' in self._played:
            self._on_referee_frame(device.version, frame)

    def _on_referee_frame(self, version: ref.ProtocolVersion, frame: bytes) -> None:
        record = ref.StatusDecoder(version).decode(ref.decode_frame(frame))
        topic, _msg_type, convert = REFEREE_TOPICS[type(record)]
        msg = convert(record)
        msg.header.stamp = self._clock.now().to_msg()
        self.host.inject(topic, msg)

    def _on_interaction(self, msg: Any, _receive_ns: int) -> None:
        self.interaction.offer(msg.content_id, msg.receiver_id, bytes(msg.content))

    def _relay_interaction(self) -> None:
        referee = self.world.referee
        if referee is None or not self.interaction.waiting:
            return
        frame = self.interaction.take(referee.rules.settings.robot_id, self.world.time_ns)
        if frame is not None:
            referee.receive(frame, self.world.time_ns)

    def _on_imu_frame(self, frame: bytes) -> None:
        reading = reading_from_sample(decode_payload(decode_frame(frame)), self._mounting)
        covariances = (_IMU_COVARIANCE,) * 3
        msg = imu_message(reading, self._clock.now().nanoseconds, self._imu_frame_id, covariances)
        self.host.inject(self._imu_topic, msg)

    # -- the robot --------------------------------------------------------------------------
    def watch(self, topic: str, *, keep_history: bool = False) -> None:
        """Keep the latest message published on topic (and, with keep_history, all).

        Topics the plugins publish arrive as they are published; /actuator_states and
        /joint_states are built from the hardware at the bridge's publish_rate, as the
        bridge publishes them.
        """
        if keep_history:
            self._history.setdefault(topic, [])
        if topic in ('/actuator_states', '/joint_states'):
            if not self._bridge_topics:
                self.on_tick(self._bridge_states)
            self._bridge_topics.add(topic)
            return
        self.host.add_local_handler(topic, lambda msg, _receive_ns: self._keep(topic, msg))

    def _keep(self, topic: str, msg: Any) -> None:
        self._latest[topic] = msg
        history = self._history.get(topic)
        if history is not None:
            history.append(msg)

    def _bridge_states(self) -> None:
        if self.world.time_ns % self._state_every:
            return
        joint_states, actuator_states = state_msgs(
            self.bridge.hardware.states(), self._clock.now().to_msg()
        )
        for topic, msg in (('/joint_states', joint_states), ('/actuator_states', actuator_states)):
            if topic in self._bridge_topics:
                self._keep(topic, msg)

    def latest(self, topic: str) -> Any:
        """The latest message published on a watched topic, or None."""
        return self._latest.get(topic)

    def history(self, topic: str) -> list[Any]:
        """A copy of every message on a topic watched with keep_history."""
        return list(self._history.get(topic, []))

    def plugin(self, name: str) -> Any:
        """The plugin instance (read-only use in tests)."""
        return self.host.plugin(name)

    def joint(self, name: str) -> dict[str, Any]:
        """The joint's state as the hardware has it: ActuatorState fields by name."""
        state = self.bridge.hardware.actuators[name].state()._asdict()
        del state['name']
        return state

    def drive_joints(self, targets: Mapping[str, Mapping[str, float]]) -> None:
        """Set joint targets on the hardware before every tick from now on, as a second
        commander on /actuator_cmd would (``{joint: set_command keyword arguments}``);
        an empty mapping stops it."""
        self._driven = dict(targets)
