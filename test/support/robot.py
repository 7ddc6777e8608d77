"""SimRobot: the whole robot (can_bridge on rm_sim + rm_robot) in this test process.

    with SimRobot(plugins=['chassis'], overrides={'rm_robot': {'chassis.rate': 100.0}}) as robot:
        robot.publish('/chassis_cmd', ChassisCmd(mode=ChassisCmd.RAW), rate_hz=20)
        robot.publish('/vel_cmd', Twist(linear=Vector3(x=1.0)), rate_hz=20)
        assert robot.wait_until(lambda: robot.world.body.x > 0.5, timeout=10.0)

The robot comes from the same parameter files `bringup --sim` uses (the robot config,
then its simulation overlay), with three changes so that robots in parallel test runs
never meet: every bus gets a channel name of its own (rm_sim's channel registry is
process-wide), the simulated IMU's pty lives in a private temporary folder, and both nodes
run in a private rclpy Context on the test's ROS domain with localhost-only discovery
(test/conftest.py). Both nodes and a driver node spin on one EventsExecutor in a
background thread, as the one-process runner does. The world runs in real time; tests
wait on conditions with generous timeouts, never on fixed sleeps.
"""

from __future__ import annotations

import os
import pathlib
import shutil
import tempfile
import threading
import time
import uuid
from collections.abc import Callable, Mapping
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, qos_profile_sensor_data
from rm_base.bridge import CanBridgeNode
from rm_base.config.param_files import load_parameters
from rm_base.host.node import RobotHost

from support.ros import wait_until

CONFIG_DIR = pathlib.Path(__file__).resolve().parents[2] / 'rm_bringup' / 'config'


#: can_bridge overrides for a shooter that behaves like the real one (the values are
#: derived in test/integration/test_shooter.py): a friction wheel's inertia on its rotor, the
#: rotor's own top speed, and the trigger disc with balls.
SHOOTER_SIM_LOADS = {
    'joints.friction_l.sim.load_inertia': 4.5e-5,
    'joints.friction_r.sim.load_inertia': 4.5e-5,
    'joints.friction_l.max_velocity': 1000.0,
    'joints.friction_r.max_velocity': 1000.0,
    'joints.trigger.sim.load_inertia': 2e-4,
}


def robot_parameters(
    config: str,
    tmp: str,
    plugins: list[str] | None = None,
    overrides: Mapping[str, Mapping[str, Any]] | None = None,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The (can_bridge, rm_robot) parameters of a robot config on rm_sim, for a test.

    As `bringup --sim` loads them, with every bus on a channel of its own (rm_sim's channel
    registry is process-wide) and the simulated IMU's terminal in the folder tmp.

    Args:
        config: robot config name in rm_bringup/config.
        tmp: a private folder.
        plugins: plugin instances to load (default: all of the config).
        overrides: ``{'can_bridge' | 'rm_robot': {flat parameter: value}}`` applied last.
    """
    files = [CONFIG_DIR / f'{config}.yaml', CONFIG_DIR / f'{config}_sim.yaml']
    params = load_parameters(f for f in files if f.exists())
    bridge, host = params.get('can_bridge', {}), params.get('rm_robot', {})
    tag = uuid.uuid4().hex[:8]
    for key in [k for k in bridge if k.startswith('buses.') and k.endswith('.interface')]:
        bus = key.split('.')[1]
        bridge[f'buses.{bus}.channel'] = f'{bus}-{tag}'
    # the simulated serial devices' terminals in tmp, as the plugins' ports
    for device, port in (('imu', 'imu.port'), ('referee', 'referee.port')):
        path = os.path.join(tmp, device)
        if f'sim.{device}.path' in bridge:
            bridge[f'sim.{device}.path'] = path
        if port in host:
            host[port] = path
    for device in ('remote', 'image_link'):
        if f'sim.{device}.path' in bridge:
            bridge[f'sim.{device}.path'] = os.path.join(tmp, device)
    # zeros and biases kept in the test's folder: never read from another test or a user's
    for values, key in ((bridge, 'calibration.file'), (host, 'imu.calibration.file')):
        if values.get(key):
            values[key] = os.path.join(tmp, 'calibration.yaml')
    if plugins is not None:
        host['plugins'] = list(plugins)
        if 'manual' in plugins:
            # rm_manual's plugin, run in rm_robot (a test drives it there, in step)
            manual = params.get('rm_manual', {})
            host.update({k: v for k, v in manual.items() if k.startswith('manual.')})
    for node, values in (overrides or {}).items():
        {'can_bridge': bridge, 'rm_robot': host}[node].update(values)
    return bridge, host


def _parameter(name: str, value: Any) -> Parameter:
    if isinstance(value, str):
        value = os.path.expandvars(value)
    return Parameter(name, value=value)


class SimRobot:
    """The simulated robot of one robot config, in this process (see module docstring).

    Args:
        config: robot config name in rm_bringup/config (``standard``, ``hero``).
        plugins: plugin instances to load (default: all of the config).
        overrides: ``{'can_bridge' | 'rm_robot': {flat parameter: value}}`` applied last.
        settle_timeout: how long to wait for the first joint states [s].
        split: run the plugins in rm_robot's own loop with /actuator_cmd and
            /actuator_states between the nodes, as two processes would (default: in the
            bridge's loop, as bringup does).
    """

    def __init__(
        self,
        config: str = 'standard',
        *,
        plugins: list[str] | None = None,
        overrides: Mapping[str, Mapping[str, Any]] | None = None,
        settle_timeout: float = 20.0,
        split: bool = False,
    ) -> None:
        self._tmp = tempfile.mkdtemp(prefix='rm_simrobot_')
        bridge, host = robot_parameters(config, self._tmp, plugins, overrides)
        self.bridge_parameters, self.host_parameters = bridge, host

        self.context = Context()
        rclpy.init(context=self.context, domain_id=int(os.environ['ROS_DOMAIN_ID']))
        self._subs: dict[str, Any] = {}
        self._latest: dict[str, Any] = {}
        self._history: dict[str, list[Any]] = {}
        self._lock = threading.Lock()
        self._publishers: dict[str, Any] = {}
        self._streams: dict[str, tuple[threading.Event, threading.Thread]] = {}
        self._stop = threading.Event()
        self.bridge: CanBridgeNode | None = None
        self.host: RobotHost | None = None
        try:
            self.bridge = CanBridgeNode(
                context=self.context,
                parameter_overrides=[_parameter(k, v) for k, v in bridge.items()],
            )
            self.host = RobotHost(
                hardware=None if split else self.bridge.hardware,
                context=self.context,
                parameter_overrides=[_parameter(k, v) for k, v in host.items()],
            )
            self.driver = rclpy.create_node('sim_robot_driver', context=self.context)
            self.executor = EventsExecutor(context=self.context)
            for node in (self.bridge, self.host, self.driver):
                self.executor.add_node(node)
            self._spinner = threading.Thread(target=self._spin, name='sim-robot', daemon=True)
            self._spinner.start()
            from rm_msgs.msg import ActuatorState

            self.subscribe('/actuator_states', ActuatorState)
            if not self.wait_until(lambda: self.latest('/actuator_states'), settle_timeout):
                raise TimeoutError('no /actuator_states from the simulated robot')
        except BaseException:
            self.close()
            raise

    # -- life cycle ---------------------------------------------------------------------
    def _spin(self) -> None:
        # EventsExecutor.spin() ignores shutdown requests on rclpy 7.1.6 (docs/ROS_FROM_WHEELS.md).
        while not self._stop.is_set() and self.context.ok():
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        """Stop streams, shut both nodes down (zero output first) and the context."""
        for name in list(self._streams):
            self.stop_publishing(name)
        if self.host is not None:
            self.host.shutdown()
        self._stop.set()
        spinner = getattr(self, '_spinner', None)
        if spinner is not None:
            spinner.join(timeout=5.0)
        for node in (self.host, self.bridge, getattr(self, 'driver', None)):
            if node is not None:
                node.destroy_node()
        executor = getattr(self, 'executor', None)
        if executor is not None:
            executor.shutdown()
        self.context.try_shutdown()
        shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self) -> SimRobot:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the simulated world --------------------------------------------------------------
    @property
    def world(self):
        """The bridge's SimWorld: body pose, motors, fault injection."""
        return self.bridge.sim_world

    def plugin(self, name: str):
        """The hosted plugin instance (read-only use in tests)."""
        return self.host.plugin(name)

    # -- topics ---------------------------------------------------------------------------
    def publish(self, topic: str, msg: Any, *, rate_hz: float | None = None) -> None:
        """Publish msg once, or keep publishing it at rate_hz until stop_publishing(topic).

        A message with a header gets a fresh stamp at every publish, as a live commander
        (or `rmcli topic pub` with `header: auto`) does.
        """
        self.stop_publishing(topic)
        pub = self._publishers.get(topic)
        if pub is None:
            pub = self.driver.create_publisher(type(msg), topic, QoSProfile(depth=10))
            self._publishers[topic] = pub
        if rate_hz is None:
            self._stamp(msg)
            pub.publish(msg)
            return
        stop = threading.Event()

        def stream() -> None:
            period = 1.0 / rate_hz
            deadline = time.monotonic()
            while not stop.is_set() and self.context.ok():
                self._stamp(msg)
                pub.publish(msg)
                deadline += period
                stop.wait(max(0.0, deadline - time.monotonic()))

        thread = threading.Thread(target=stream, name=f'publish{topic}', daemon=True)
        self._streams[topic] = (stop, thread)
        thread.start()

    def stop_publishing(self, topic: str) -> None:
        """Stop a stream started by publish(..., rate_hz=...)."""
        stream = self._streams.pop(topic, None)
        if stream is not None:
            stream[0].set()
            stream[1].join(timeout=2.0)

    def _stamp(self, msg: Any) -> None:
        if hasattr(msg, 'header'):
            msg.header.stamp = self.driver.get_clock().now().to_msg()

    def subscribe(self, topic: str, msg_type: Any, *, keep_history: bool = False) -> None:
        """Keep the latest message of topic (and, with keep_history, all of them)."""
        if topic in self._subs:
            return
        if keep_history:
            self._history[topic] = []

        def store(msg: Any) -> None:
            with self._lock:
                self._latest[topic] = msg
                if topic in self._history:
                    self._history[topic].append(msg)

        self._subs[topic] = self.driver.create_subscription(
            msg_type, topic, store, qos_profile_sensor_data
        )

    def latest(self, topic: str) -> Any:
        """The latest message received on a subscribed topic, or None."""
        with self._lock:
            return self._latest.get(topic)

    def history(self, topic: str) -> list[Any]:
        """A copy of every message received on a topic subscribed with keep_history."""
        with self._lock:
            return list(self._history.get(topic, []))

    def joint(self, name: str) -> dict[str, float]:
        """The joint's latest values from /actuator_states (position, velocity, ...)."""
        msg = self.latest('/actuator_states')
        index = list(msg.name).index(name)
        fields = (
            'position',
            'velocity',
            'effort',
            'temperature',
            'online',
            'error_code',
            'mode',
            'command',
        )
        return {f: getattr(msg, f)[index] for f in fields}

    @staticmethod
    def wait_until(predicate: Callable[[], Any], timeout: float) -> bool:
        """Poll predicate every 10 ms until true or timeout [s] (the executor spins apart)."""
        return wait_until(lambda: bool(predicate()), timeout)
