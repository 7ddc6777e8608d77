"""PluginBase through its public API: lifecycle, zero output, watchdog, state, errors."""

import enum
import math

import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rm_base.plugin import (
    DefaultState,
    JointClaimError,
    JointTarget,
    Mode,
    ParameterError,
    PluginBase,
    PluginInitError,
    PluginParams,
    TargetRejectedError,
)
from rm_base.plugin.node_io import DdsJointIO
from support.ros import wait_until
from support.wheel_plugin import MS, T0, Wheel, WheelPlugin, at, command, modes

from rm_msgs.msg import ActuatorCmd, ActuatorState, PluginState

pytestmark = pytest.mark.ros

@pytest.fixture
def node(ros_context):
    node = rclpy.create_node(
        'plugin_test', context=ros_context,
        parameter_overrides=[Parameter('wheel.gain', value=2.0)],
    )
    yield node
    node.destroy_node()


@pytest.fixture
def io(node):
    """The plugin I/O the node's plugins share, as a host gives it to each."""
    return DdsJointIO(node)


@pytest.fixture
def sent(io, monkeypatch):
    """ActuatorCmd messages published through the node's shared publisher, in order."""
    publisher = io.actuator_cmd
    messages = []
    original = publisher.publish

    def record(msg):
        messages.append(msg)
        original(msg)

    monkeypatch.setattr(publisher, 'publish', record)
    return messages


@pytest.fixture
def plugin(node, io):
    plugin = WheelPlugin()
    plugin.init(node, 'wheel', PluginParams(node, 'wheel', 'test/Wheel'), io)
    return plugin


def test_after_init_the_plugin_is_disabled_in_its_safe_state(plugin):
    assert not plugin.enabled
    assert plugin.state is Wheel.PASSIVE
    assert plugin.rate == 100.0  # default of <name>.rate [Hz]
    assert plugin.command_timeout == 0.1  # default of <name>.command_timeout [s]
    assert plugin.joints == ('wheel',)
    assert plugin.gain == 2.0


def test_before_init_the_state_and_the_joints_say_init_is_missing():
    plugin = WheelPlugin()
    with pytest.raises(RuntimeError, match=r'WheelPlugin: call init\(\) first'):
        _ = plugin.state
    with pytest.raises(RuntimeError, match=r'call init\(\) first'):
        plugin.zero_output()


def test_run_while_disabled_does_nothing(plugin, sent):
    command(plugin, 1.0, T0)
    plugin.run(at(T0))
    assert plugin.events == [] and sent == []


def test_enable_resets_and_forgets_commands_received_before(plugin, sent):
    command(plugin, 1.0, T0)
    plugin.enable()
    assert plugin.events == ['reset']
    assert plugin.enabled
    # The command that arrived while disabled must not be acted on.
    plugin.run(at(T0 + 1 * MS))
    assert plugin.state is Wheel.PASSIVE
    assert plugin.reason == 'no command on /wheel_cmd yet'
    assert [modes(m) for m in sent] == [{'wheel': Mode.OFF}]


def test_with_a_fresh_command_update_runs_and_sends_targets(plugin, sent):
    plugin.enable()
    command(plugin, 1.5, T0)
    plugin.run(at(T0 + 10 * MS), dt=0.01)
    assert plugin.state is Wheel.DRIVE
    assert plugin.events[-1] == ('update', 0.01)
    assert list(sent[-1].name) == ['wheel']
    assert list(sent[-1].mode) == [ActuatorCmd.MODE_VELOCITY]
    assert list(sent[-1].velocity) == [3.0]  # gain 2.0 * 1.5 rad/s


def test_when_run_sends_targets_expect_them_stamped_with_the_ticks_now(plugin, sent):
    plugin.enable()
    command(plugin, 1.5, T0)
    plugin.run(at(T0 + 10 * MS))
    # T0 + 10 ms = 1000.010 s: the now given to run(), not the clock's at publish time
    assert (sent[-1].header.stamp.sec, sent[-1].header.stamp.nanosec) == (1000, 10 * MS)


def wheel_state(stamp_ns):
    msg = ActuatorState(name=['wheel'], position=[0.0], velocity=[0.0], effort=[0.0],
                        temperature=[0.0], online=[True], error_code=[0])
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
    return msg


def test_targets_carry_the_stamp_of_the_states_their_run_started_with(plugin, sent):
    plugin.joint_states.handle(wheel_state(T0), receive_ns=T0)
    plugin.enable()
    command(plugin, 1.5, T0)
    real_update = plugin.update

    def update(now, dt):  # newer states arrive while the plugin runs
        plugin.joint_states.handle(wheel_state(T0 + 3 * MS), receive_ns=T0 + 3 * MS)
        real_update(now, dt)

    plugin.update = update
    plugin.run(at(T0 + 5 * MS))
    stamp = sent[-1].states_stamp
    assert (stamp.sec, stamp.nanosec) == (1000, 0)  # T0: what the run started from
    plugin.disable()  # outside a run: the view now
    stamp = sent[-1].states_stamp
    assert (stamp.sec, stamp.nanosec) == (1000, 3 * MS)


def test_when_disabled_outside_a_tick_expect_zero_output_stamped_by_the_clock(plugin, node, sent):
    plugin.enable()
    before = node.get_clock().now().nanoseconds
    plugin.disable()
    stamp = sent[-1].header.stamp
    assert stamp.sec * 1_000_000_000 + stamp.nanosec >= before


def test_dt_defaults_to_the_clock_difference_and_to_the_period_first(plugin):
    plugin.enable()
    command(plugin, 1.0, T0)
    plugin.run(at(T0))
    plugin.run(at(T0 + 4 * MS))
    # First tick after enable: nominal period 1/100 Hz = 0.01 s; then 4 ms.
    assert [e for e in plugin.events if e != 'reset'] == [('update', 0.01), ('update', 0.004)]


def test_on_a_clock_that_stands_still_or_goes_back_the_timing_stays_sane(plugin):
    # The finding: on /clock (40 Hz from a replay) the 200 Hz chassis ran with dt 0 and
    # failed every tick; a replay that starts over sends the clock back.
    plugin.enable()
    command(plugin, 1.0, T0)
    plugin.run(at(T0))
    plugin.run(at(T0))  # the clock stood still: nothing to do
    plugin.run(at(T0 + 25 * MS))
    command(plugin, 1.0, T0 - 500 * MS)
    plugin.run(at(T0 - 500 * MS))  # went back: the nominal period again
    updates = [e for e in plugin.events if e != 'reset']
    assert updates == [('update', 0.01), ('update', 0.025), ('update', 0.01)]


def test_when_command_times_out_expect_safe_state_reason_reset_and_zero_output(plugin, sent):
    plugin.enable()
    command(plugin, 1.0, T0)
    plugin.run(at(T0 + 50 * MS))
    assert plugin.integral > 0.0
    plugin.run(at(T0 + 150 * MS))  # 150 ms > 100 ms timeout
    assert plugin.state is Wheel.PASSIVE
    assert plugin.reason == 'no command on /wheel_cmd for 0.150 s (timeout 0.100 s)'
    assert plugin.integral == 0.0  # on_reset ran when the command was lost
    assert modes(sent[-1]) == {'wheel': Mode.OFF}
    # Still lost on the next tick: zero output again, no further reset.
    resets = plugin.events.count('reset')
    plugin.run(at(T0 + 160 * MS))
    assert modes(sent[-1]) == {'wheel': Mode.OFF}
    assert plugin.events.count('reset') == resets


def test_when_command_returns_expect_update_again(plugin, sent):
    plugin.enable()
    plugin.run(at(T0))
    assert plugin.state is Wheel.PASSIVE
    command(plugin, 1.0, T0 + 5 * MS)
    plugin.run(at(T0 + 6 * MS))
    assert plugin.state is Wheel.DRIVE
    assert list(sent[-1].mode) == [ActuatorCmd.MODE_VELOCITY]


def test_disable_commands_zero_output_before_anything_else(plugin, sent):
    plugin.enable()
    command(plugin, 1.0, T0)
    plugin.run(at(T0))

    published_before_hook = []
    plugin.on_disable = lambda: published_before_hook.append(len(sent))
    plugin.disable('operator')
    assert modes(sent[-1]) == {'wheel': Mode.OFF}
    assert published_before_hook == [len(sent)]
    assert not plugin.enabled
    assert plugin.state is Wheel.PASSIVE
    assert plugin.reason == 'operator'
    assert plugin.integral == 0.0


def test_disable_when_already_disabled_still_zeroes_output(plugin, sent):
    plugin.disable()
    assert [modes(m) for m in sent] == [{'wheel': Mode.OFF}]


def test_when_update_raises_expect_no_exception_zero_output_and_safe_state(plugin, sent):
    plugin.enable()
    command(plugin, 1.0, T0)
    plugin.run(at(T0))

    def broken(now, dt):
        raise ZeroDivisionError('wheel radius is 0')

    plugin.update = broken
    plugin.run(at(T0 + 1 * MS))
    assert plugin.error_count == 1
    assert modes(sent[-1]) == {'wheel': Mode.OFF}
    assert plugin.state is Wheel.PASSIVE
    assert plugin.reason == 'run failed: ZeroDivisionError: wheel radius is 0'


def test_when_a_target_is_nan_expect_nothing_published_but_zero_output(plugin, sent):
    plugin.enable()
    command(plugin, math.nan, T0)
    plugin.run(at(T0))
    assert sent
    assert all(list(m.mode) == [ActuatorCmd.MODE_OFF] for m in sent)
    assert plugin.error_count == 1
    assert "joint 'wheel': velocity is not a finite number" in plugin.reason


def test_send_rejects_joints_the_plugin_did_not_claim(plugin, sent):
    with pytest.raises(
        TargetRejectedError, match=r'does not drive joint\(s\) yaw \(claimed: wheel\)'
    ):
        plugin.send_joint_targets({'yaw': JointTarget.off()})
    assert sent == []


def test_two_plugins_cannot_drive_the_same_joint(node, io, plugin):
    other = WheelPlugin()
    with pytest.raises(
        JointClaimError,
        match=r"plugin 'other' cannot drive joint 'wheel' \(already driven by plugin 'wheel'\)",
    ):
        other.init(node, 'other', io=io)


def test_state_is_published_on_transition(node, plugin):
    received = []
    node.create_subscription(PluginState, '~/wheel/state', received.append, 10)
    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    try:
        wait_until(lambda: node.count_publishers('/plugin_test/wheel/state') > 0, 5.0)
        plugin.enable()
        command(plugin, 1.0, T0)
        plugin.run(at(T0))

        assert wait_until(
            lambda: any(m.state_name == 'DRIVE' for m in received), 5.0,
            spin=lambda t: executor.spin_once(timeout_sec=t),
        )
        drive = next(m for m in received if m.state_name == 'DRIVE')
        assert (drive.plugin, drive.type, drive.enabled) == ('wheel', 'test/Wheel', True)
        assert drive.state == Wheel.DRIVE.value
        assert drive.reason == 'commanded'
    finally:
        executor.shutdown()


def test_joint_states_come_from_actuator_states(node, plugin):
    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    publisher = node.create_publisher(ActuatorState, '/actuator_states', 10)
    msg = ActuatorState(
        name=['wheel'], position=[1.25], velocity=[3.0], effort=[0.4], temperature=[35.0],
        online=[True], error_code=[0], mode=[ActuatorCmd.MODE_VELOCITY], command=[0.4],
    )
    try:
        assert wait_until(
            lambda: plugin.joint_states.get('wheel') is not None, 5.0,
            spin=lambda t: (publisher.publish(msg), executor.spin_once(timeout_sec=t)),
        )
        state = plugin.joint_states.get('wheel')
        assert (state.position, state.velocity, state.online) == (1.25, 3.0, True)
    finally:
        executor.shutdown()


def test_when_on_init_raises_expect_one_init_error_naming_the_plugin(node):
    class Broken(PluginBase):
        def on_init(self):
            raise OSError('cannot open /dev/ttyUSB0')

    with pytest.raises(
        PluginInitError,
        match=r"^plugin 'imu' \(rm_plugins/Hi220\): init failed: "
        r'OSError: cannot open /dev/ttyUSB0$',
    ) as info:
        Broken().init(node, 'imu', PluginParams(node, 'imu', 'rm_plugins/Hi220'))
    assert info.value.plugin == 'imu'


def test_when_a_required_parameter_is_missing_expect_error_naming_plugin_and_key(node):
    class NeedsRadius(PluginBase):
        def on_init(self):
            self.params.double('wheel_radius', description='wheel radius', unit='m', gt=0.0)

    with pytest.raises(
        ParameterError,
        match=r"^plugin 'chassis' \(x/Y\): parameter 'chassis.wheel_radius' is required",
    ):
        NeedsRadius().init(node, 'chassis', PluginParams(node, 'chassis', 'x/Y'))


def test_a_plugin_may_not_override_framework_methods():
    with pytest.raises(TypeError, match=r'overrides PluginBase.run\(\).*override the hooks'):

        class Sneaky(PluginBase):
            def run(self, now, dt=None):
                pass


def test_states_need_a_safe_state():
    class Modes(enum.IntEnum):
        IDLE = 0
        GO = 1

    with pytest.raises(TypeError, match='needs SAFE_STATE or a State member named PASSIVE'):

        class NoSafe(PluginBase):
            State = Modes

    class WithSafe(PluginBase):
        State = Modes
        SAFE_STATE = Modes.IDLE

    assert WithSafe().safe_state is Modes.IDLE


def test_state_values_must_fit_plugin_state_uint8():
    class Big(enum.IntEnum):
        PASSIVE = 0
        HUGE = 300

    with pytest.raises(TypeError, match=r'State.HUGE must have an int value in 0..255'):

        class TooBig(PluginBase):
            State = Big


def test_default_states_are_passive_and_active():
    assert PluginBase().safe_state is DefaultState.PASSIVE
    assert [s.name for s in DefaultState] == ['PASSIVE', 'ACTIVE']
