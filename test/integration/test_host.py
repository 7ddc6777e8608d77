"""rm_robot in-process: plugins from a package rm_base never heard of, rates, watchdog, services.

Why one module: every test shares the host, probe and installed-fixture set-up.

Each test builds a RobotHost in a private Context with parameter_overrides, spins it with
an EventsExecutor in a background thread (as main() does, spin_once in a loop) and
watches it through a probe node. The plugins come from test/fixtures/rm_extra_plugins,
installed with colcon into a temporary prefix that is put on AMENT_PREFIX_PATH.
"""

import itertools
import os
import pathlib
import re
import threading
import time

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from fixtures.extra_plugins import install_extra_plugins
from geometry_msgs.msg import TwistStamped
from rclpy.duration import Duration
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rm_base.errors import ConfigError
from rm_base.host import RobotHost
from rm_base.host.main import make_executor
from rm_base.plugin import (
    STATE_QOS,
    JointClaimError,
    ParameterError,
    PluginInitError,
    PluginLoader,
    PluginNotFoundError,
)
from std_msgs.msg import UInt64
from std_srvs.srv import SetBool
from support.ros import wait_until

from rm_msgs.msg import ActuatorCmd, PluginState

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

RM_BASE_SOURCES = pathlib.Path(__file__).resolve().parents[2] / 'rm_base' / 'rm_base'

# Rates are checked to +-20 %: generous for a 2-vCPU VM with CPU steal, tight enough to
# tell 50 Hz from 200 Hz and to see a plugin dragged down by a slow neighbour.
RATE_TOLERANCE = 0.20
WAIT = 10.0  # longest wait for any condition [s]; normally met in well under a second


@pytest.fixture
def extra_plugins(tmp_path_factory, monkeypatch):
    install = install_extra_plugins(str(tmp_path_factory.getbasetemp()))
    monkeypatch.setenv(
        'AMENT_PREFIX_PATH', f'{install.prefix}{os.pathsep}{os.environ["AMENT_PREFIX_PATH"]}'
    )
    monkeypatch.syspath_prepend(str(install.site_packages))
    return install


class Harness:
    """A RobotHost and a probe node on one EventsExecutor spun in a background thread."""

    def __init__(self, context, **overrides):
        self.host = RobotHost(
            context=context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )
        self.probe = rclpy.create_node('probe', context=context)
        self.executor = EventsExecutor(context=context)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._command = None

    def collect(self, msg_type, topic, qos=10):
        received = []
        self.probe.create_subscription(msg_type, topic, received.append, qos)
        return received

    def client(self, name):
        return self.probe.create_client(SetBool, name)

    def publish_echo_commands(self, velocity, topic='echo_cmd', period=0.02):
        """Publish TwistStamped(linear.x=velocity) every period [s] until stop_commands()."""
        publisher = self.probe.create_publisher(TwistStamped, topic, 10)
        self._command = threading.Event()
        self._command.set()

        def tick():
            if self._command.is_set():
                msg = TwistStamped()
                msg.header.stamp = self.probe.get_clock().now().to_msg()
                msg.twist.linear.x = velocity
                publisher.publish(msg)

        self.probe.create_timer(period, tick)

    def stop_commands(self):
        self._command.clear()

    def start(self):
        self.executor.add_node(self.host)
        self.executor.add_node(self.probe)
        self._thread.start()
        return self

    def call(self, client, data):
        assert client.wait_for_service(timeout_sec=WAIT)
        future = client.call_async(SetBool.Request(data=data))
        assert wait_until(future.done, WAIT)
        return future.result()

    def close(self):
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
        self.host.destroy_node()
        self.probe.destroy_node()
        self.executor.shutdown()

    def _spin(self):
        # EventsExecutor.spin() from a thread received nothing here (rclpy 7.1.6); spin_once
        # in a loop works, as in main().
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)


@pytest.fixture
def harness(ros_context, extra_plugins):
    made = []

    def make(**overrides):
        made.append(Harness(ros_context, **overrides))
        return made[-1]

    yield make
    for h in made:
        h.close()


def rate_over(plugins, ticks):
    """Counter plugins' rates [Hz] from the median interval of their next ticks[name] runs.

    The median, not the mean: a run a stall of this shared machine delayed changes one or
    two intervals, not the rate the loop schedules (the schedule itself is checked exactly
    on a simulated clock in test/unit/host/test_plugin_task.py).
    """
    starts = {name: len(p.tick_ns) for name, p in plugins.items()}
    assert wait_until(
        lambda: all(len(p.tick_ns) > starts[n] + ticks[n] for n, p in plugins.items()), WAIT
    )
    rates = {}
    for name, plugin in plugins.items():
        stamps = list(plugin.tick_ns)[starts[name]:starts[name] + ticks[name] + 1]
        intervals = sorted(b - a for a, b in itertools.pairwise(stamps))
        rates[name] = 1e9 / intervals[len(intervals) // 2]
    return rates


def within(measured, nominal):
    return abs(measured - nominal) <= RATE_TOLERANCE * nominal


def counter(name, rate, **extra):
    params = {f'{name}.type': 'rm_extra_plugins/Counter', f'{name}.rate': rate}
    params.update({f'{name}.{k}': v for k, v in extra.items()})
    return params


def echo(name='echo', rate=100.0, **extra):
    params = {
        f'{name}.type': 'rm_extra_plugins/VelocityEcho',
        f'{name}.rate': rate,
        f'{name}.joints': ['left_wheel', 'right_wheel'],
    }
    params.update({f'{name}.{k}': v for k, v in extra.items()})
    return params


def all_off(msg):
    return len(msg.mode) > 0 and all(m == ActuatorCmd.MODE_OFF for m in msg.mode)


def test_a_plugin_from_a_package_rm_base_never_heard_of_loads_by_name(harness, extra_plugins):
    # rm_base names no plugin package anywhere; the plugin is found via the ament index.
    assert not [p for p in RM_BASE_SOURCES.rglob('*.py') if 'rm_extra_plugins' in p.read_text()]
    description = PluginLoader().describe('rm_extra_plugins/Counter')
    assert description.package == 'rm_extra_plugins'
    assert description.xml_path.startswith(str(extra_plugins.prefix))

    h = harness(plugins=['counter'], **counter('counter', 100.0))
    counts = h.collect(UInt64, '/counter/count')
    h.start()
    plugin = h.host.plugin('counter')
    assert type(plugin).__module__ == 'rm_extra_plugins.counter'
    assert wait_until(lambda: len(counts) >= 10, WAIT)
    assert counts[-1].data > counts[0].data


def test_two_instances_run_side_by_side_at_their_own_rates(harness):
    h = harness(plugins=['slow', 'fast'], **counter('slow', 50.0), **counter('fast', 200.0))
    h.start()
    slow, fast = h.host.plugin('slow'), h.host.plugin('fast')
    assert wait_until(lambda: slow.count >= 3, WAIT)  # past start-up
    # Over the same second: 50 ticks of the slow one, 200 of the fast one.
    rates = rate_over({'slow': slow, 'fast': fast}, ticks={'slow': 50, 'fast': 200})
    assert within(rates['slow'], 50.0), rates
    assert within(rates['fast'], 200.0), rates


def test_a_slow_plugin_shows_in_the_loop_timing_and_skips(harness):
    # One loop thread runs every plugin, as firmware does: hog burns 30 ms per run at a
    # 20 ms period, so the loop is late after each of its runs and both plugins skip
    # deadlines; the loop's own timing names the hog as the expensive component.
    h = harness(
        plugins=['fast', 'hog'], **counter('fast', 200.0), **counter('hog', 50.0, busy_time=0.03)
    )
    h.start()
    hog = h.host.plugin('hog')
    assert wait_until(lambda: hog.count >= 5, WAIT)
    timing = dict(h.host.loop.component_stats())
    assert timing['plugin hog'].p50_us >= 25_000, timing  # 30 ms of busy time per run
    assert timing['plugin fast'].p50_us < 5_000, timing
    assert h.host.task('hog').skipped > 0
    assert h.host.task('fast').skipped > 0
    assert h.host.loop.stats().skipped_ticks > 0


def publish_once(h, velocity, topic='echo_cmd'):
    publisher = h.probe.create_publisher(TwistStamped, topic, 10)
    assert wait_until(lambda: publisher.get_subscription_count() > 0, WAIT)
    msg = TwistStamped()
    msg.header.stamp = h.probe.get_clock().now().to_msg()
    msg.twist.linear.x = velocity
    publisher.publish(msg)
    return time.monotonic()


def test_when_a_command_arrives_expect_a_run_at_once_not_at_the_next_tick(harness):
    # 0.5 Hz: the next deadline is up to 2 s away; the command is on /actuator_cmd at once.
    h = harness(plugins=['echo'], **echo(rate=0.5, command_timeout=5.0, run_on_command=True))
    cmds = h.collect(ActuatorCmd, '/actuator_cmd')
    h.start()
    task = h.host.task('echo')
    assert wait_until(lambda: task.ticks >= 1, WAIT)  # the first run, at enable
    sent = publish_once(h, 1.5)
    assert wait_until(lambda: cmds and list(cmds[-1].velocity) == [1.5, 1.5], WAIT)
    latency = time.monotonic() - sent
    print(f'command -> /actuator_cmd at 0.5 Hz: {1e3 * latency:.0f} ms; '
          f'{task.command_runs} run(s) for the command, {task.ticks} in all')
    assert task.command_runs == 1
    assert latency < 0.5  # [s] (milliseconds; the next deadline was up to 2 s away)


def test_when_run_on_command_is_off_expect_the_next_tick_only(harness):
    h = harness(plugins=['echo'], **echo(rate=0.5, command_timeout=5.0, run_on_command=False))
    cmds = h.collect(ActuatorCmd, '/actuator_cmd')
    h.start()
    task = h.host.task('echo')
    assert wait_until(lambda: task.ticks >= 1, WAIT)
    publish_once(h, 1.5)
    assert wait_until(lambda: cmds and list(cmds[-1].velocity) == [1.5, 1.5], WAIT)
    assert task.command_runs == 0  # the command went out with a scheduled run


def test_when_the_command_stops_expect_passive_with_the_reason_and_zero_output(harness):
    h = harness(plugins=['echo'], **echo(command_timeout=0.2))
    states = h.collect(PluginState, '/rm_robot/echo/state', STATE_QOS)
    cmds = h.collect(ActuatorCmd, '/actuator_cmd')
    h.publish_echo_commands(1.5)
    h.start()

    assert wait_until(lambda: any(s.state_name == 'TRACKING' for s in states), WAIT)
    assert wait_until(lambda: cmds and list(cmds[-1].velocity) == [1.5, 1.5], WAIT)
    assert list(cmds[-1].mode) == [ActuatorCmd.MODE_VELOCITY] * 2

    h.stop_commands()
    assert wait_until(lambda: states[-1].state_name == 'PASSIVE', WAIT)
    reason = states[-1].reason
    match = re.fullmatch(r'no command on /echo_cmd for (\S+) s \(timeout 0\.200 s\)', reason)
    assert match, reason
    assert float(match.group(1)) >= 0.2  # not before the timeout (age printed to 1 ms)
    assert states[-1].enabled
    # Zero output from then on (the watchdog repeats it every tick).
    assert wait_until(lambda: all_off(cmds[-1]), WAIT)
    assert list(cmds[-1].name) == ['left_wheel', 'right_wheel']


def test_enable_service_disables_and_enables_one_plugin(harness):
    h = harness(plugins=['echo', 'other'], **echo(), **counter('other', 100.0))
    states = h.collect(PluginState, '/rm_robot/echo/state', STATE_QOS)
    cmds = h.collect(ActuatorCmd, '/actuator_cmd')
    enable_echo = h.client('/rm_robot/echo/enable')
    h.publish_echo_commands(1.0)
    h.start()
    other = h.host.plugin('other')
    assert wait_until(lambda: cmds and cmds[-1].velocity[0] == 1.0, WAIT)

    response = h.call(enable_echo, False)
    assert response.success and response.message == 'echo: disabled'
    assert wait_until(lambda: not states[-1].enabled, WAIT)
    assert states[-1].reason == 'disabled by service call'
    # While the other plugin ticks on, echo publishes nothing more: its last word was OFF.
    sent = len(cmds)
    ticks = other.count
    assert wait_until(lambda: other.count >= ticks + 20, WAIT)
    assert all_off(cmds[-1])
    assert len(cmds) == sent

    response = h.call(enable_echo, True)
    assert response.success and response.message == 'echo: enabled'
    assert wait_until(lambda: cmds[-1].velocity[0] == 1.0, WAIT)
    assert h.call(enable_echo, True).message == 'echo: already enabled'


def test_enable_all_service_switches_every_plugin(harness):
    h = harness(plugins=['a', 'b'], **counter('a', 100.0), **counter('b', 100.0))
    enable_all = h.client('/rm_robot/enable_all')
    h.start()
    a, b = h.host.plugin('a'), h.host.plugin('b')

    response = h.call(enable_all, False)
    assert response.success
    assert response.message == 'a: disabled; b: disabled'
    frozen = (a.count, b.count)
    assert not a.enabled and not b.enabled

    response = h.call(enable_all, True)
    assert response.success
    assert wait_until(lambda: a.count > frozen[0] + 5 and b.count > frozen[1] + 5, WAIT)


def test_plugins_disabled_in_the_config_start_disabled(harness):
    h = harness(plugins=['a'], **counter('a', 100.0, enabled=False))
    states = h.collect(PluginState, '/rm_robot/a/state', STATE_QOS)
    h.start()
    assert wait_until(lambda: states, WAIT)
    assert not states[-1].enabled
    assert h.host.plugin('a').count == 0


def test_the_config_of_a_plugin_not_loaded_is_named_not_refused(harness):
    # a robot file's ui: section under an overlay whose plugin list leaves ui out
    h = harness(plugins=['a'], **counter('a', 100.0), **{
        'ui.type': 'rm_plugins/ClientUi', 'ui.rate': 8.0, 'ui.aim_x': 960})
    assert h.host.plugin_names == ['a']


def test_state_is_published_periodically(harness):
    h = harness(plugins=['a'], state_period=0.05, **counter('a', 100.0))
    states = h.collect(PluginState, '/rm_robot/a/state', STATE_QOS)
    h.start()
    assert wait_until(lambda: any(s.state_name == 'ACTIVE' for s in states), WAIT)
    first = next(i for i, s in enumerate(states) if s.state_name == 'ACTIVE')
    # No transition after ACTIVE, yet the state keeps coming: the heartbeat.
    assert wait_until(lambda: len(states) >= first + 4, WAIT)
    heartbeat = states[first + 3]
    assert (heartbeat.plugin, heartbeat.type) == ('a', 'rm_extra_plugins/Counter')
    assert (heartbeat.state_name, heartbeat.reason, heartbeat.enabled) == (
        'ACTIVE', 'counting', True
    )


def test_the_inbox_reports_what_it_took_per_topic_on_diagnostics(harness):
    h = harness(plugins=['echo'], state_period=0.05, **echo(rate=50.0, command_timeout=5.0))
    diagnostics = h.collect(DiagnosticArray, '/diagnostics')
    h.start()
    publish_once(h, 1.0)

    def inbox_status():
        statuses = [s for m in diagnostics for s in m.status if s.name == 'rm_robot: inbox']
        return statuses[-1] if statuses else None

    assert wait_until(
        lambda: (s := inbox_status()) is not None
        and {kv.key: kv.value for kv in s.values}.get('/echo_cmd taken') == '1', WAIT)
    status = inbox_status()
    assert (status.level, status.message) == (DiagnosticStatus.OK, 'ok')
    assert {kv.key: kv.value for kv in status.values}['/echo_cmd dropped'] == '0'


def test_commands_the_plugins_refused_are_counted_on_diagnostics(harness):
    h = harness(plugins=['echo'], state_period=0.05, **echo(rate=50.0, command_timeout=0.5))
    diagnostics = h.collect(DiagnosticArray, '/diagnostics')
    h.start()
    publisher = h.probe.create_publisher(TwistStamped, 'echo_cmd', 10)
    assert wait_until(lambda: publisher.get_subscription_count() > 0, WAIT)
    stale = TwistStamped()
    stale.header.stamp = (h.probe.get_clock().now() - Duration(seconds=10.0)).to_msg()
    for _ in range(2):
        publisher.publish(stale)

    def commands_statuses():
        return [s for m in diagnostics for s in m.status if s.name == 'rm_robot: commands']

    def rejected(status):
        return {kv.key: kv.value for kv in status.values}['echo /echo_cmd rejected']

    assert wait_until(lambda: any(rejected(s) == '2' for s in commands_statuses()), WAIT)
    # one report, or two if one fell between the messages: each says what was new
    warned = [s for s in commands_statuses() if s.level == DiagnosticStatus.WARN]
    assert warned and all(
        re.fullmatch(r'rejected since the last report: [12] on /echo_cmd \(echo\), the newest: '
                     r'stale: stamp is 10\.\d{3} s old, timeout 0\.500 s', s.message)
        for s in warned), [s.message for s in warned]
    # the next report has nothing new: OK, the count kept
    assert wait_until(lambda: commands_statuses()[-1].level == DiagnosticStatus.OK, WAIT)
    assert rejected(commands_statuses()[-1]) == '2'


def test_shutdown_disables_every_plugin_with_zero_output(harness):
    h = harness(plugins=['echo', 'a'], **echo(), **counter('a', 100.0))
    cmds = h.collect(ActuatorCmd, '/actuator_cmd')
    h.publish_echo_commands(2.0)
    h.start()
    assert wait_until(lambda: cmds and cmds[-1].velocity[0] == 2.0, WAIT)

    h.host.shutdown()
    assert not h.host.plugin('echo').enabled and not h.host.plugin('a').enabled
    assert h.host.plugin('echo').reason == 'shutting down'
    assert wait_until(lambda: all_off(cmds[-1]), WAIT)
    assert not h.host.loop.running


@pytest.mark.parametrize(
    ('overrides', 'error', 'message'),
    [
        (
            {'plugins': ['chassis'], 'chassis.type': 'rm_extra_plugins/Nope'},
            PluginNotFoundError,
            r"^plugin 'chassis': unknown plugin type 'rm_extra_plugins/Nope'; available: "
            r'.*rm_extra_plugins/Counter, rm_extra_plugins/Faulty, rm_extra_plugins/VelocityEcho',
        ),
        (
            {'plugins': ['imu'], 'imu.type': 'rm_extra_plugins/Faulty'},
            PluginInitError,
            r"^plugin 'imu' \(rm_extra_plugins/Faulty\): init failed: OSError: "
            r'cannot open /dev/ttyRM0: no such device$',
        ),
        (
            {'plugins': ['echo'], 'echo.type': 'rm_extra_plugins/VelocityEcho'},
            ParameterError,
            r"^plugin 'echo' \(rm_extra_plugins/VelocityEcho\): parameter 'echo.joints' "
            r'is required but not set',
        ),
        (
            {**echo(), 'plugins': ['echo'], 'echo.rate': 'fast'},
            ParameterError,
            r"^plugin 'echo' \(rm_extra_plugins/VelocityEcho\): parameter 'echo.rate' "
            r"must be double \[Hz\]; got str 'fast'$",
        ),
        (
            {'plugins': ['chassis']},
            ParameterError,
            r"^plugin 'chassis': parameter 'chassis.type' is required but not set",
        ),
        ({}, ParameterError, r"^parameter 'plugins' is required but not set"),
        ({'plugins': ['bad name']}, ParameterError, r"'bad name' is not a valid plugin name"),
        (
            {**echo('left'), **echo('right'), 'plugins': ['left', 'right']},
            JointClaimError,
            r"^plugin 'right' cannot drive joint 'left_wheel' \(already driven by plugin 'left'\)",
        ),
        (
            # rclpy would keep a value nobody declares and say nothing
            {**echo(), 'plugins': ['echo'], 'echo.ratee': 50.0, 'state_perod': 0.5},
            ParameterError,
            r"^rm_robot: unknown parameter\(s\) 'echo.ratee' \(did you mean 'echo.rate'\?\), "
            r"'state_perod' \(did you mean 'state_period'\?\): no plugin",
        ),
    ],
    ids=[
        'unknown-type', 'init-fails', 'missing-key', 'ill-typed-key', 'missing-type',
        'no-plugins', 'bad-name', 'joint-twice', 'misspelled-keys',
    ],
)
def test_a_bad_config_gives_one_clear_error(ros_context, extra_plugins, overrides, error, message):
    with pytest.raises(error, match=message) as info:
        RobotHost(
            context=ros_context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )
    assert isinstance(info.value, ConfigError)
    assert '\n' not in str(info.value)
    assert 'other_framework/Thing' not in str(info.value)  # another base class's plugin


@pytest.mark.parametrize(
    ('kind', 'executor_type'),
    [('events', 'EventsExecutor'), ('single_threaded', 'SingleThreadedExecutor')],
)
def test_the_executor_parameter_selects_the_executor(
    ros_context, extra_plugins, kind, executor_type
):
    host = RobotHost(
        context=ros_context,
        parameter_overrides=[
            Parameter(k, value=v)
            for k, v in {'plugins': ['a'], 'executor': kind, **counter('a', 10.0)}.items()
        ],
    )
    try:
        executor = make_executor(host)
        assert type(executor).__name__ == executor_type
        executor.shutdown()
    finally:
        host.destroy_node()


def test_when_the_plugins_clock_fails_expect_the_plugin_off_with_the_reason(
    ros_context, extra_plugins
):
    # Something outside plugin.run() (here the clock) raises: the plugin is disabled,
    # zero output first, with the error as its reason; the loop goes on.
    def broken_clock():
        raise RuntimeError('clock gone')

    host = RobotHost(
        context=ros_context,
        now=broken_clock,
        parameter_overrides=[
            Parameter(k, value=v) for k, v in {'plugins': ['a'], **counter('a', 100.0)}.items()
        ],
    )
    try:
        plugin = host.plugin('a')
        assert wait_until(lambda: not plugin.enabled, WAIT)
        assert plugin.reason == 'loop failed: RuntimeError: clock gone'
        assert host.task('a').errors == 1
        assert host.loop.running
    finally:
        host.destroy_node()
