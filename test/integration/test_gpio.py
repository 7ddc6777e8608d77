"""rm_plugins/UpboardGpio in rm_robot (in-process): /gpio_cmd in, /gpio_state out.

Each test builds a RobotHost with the GPIO plugin on the simulated backend in a private
Context, spins it with a probe node on an EventsExecutor in a background thread, and talks
to it through its topics only. The ball switch is bound to the ``trigger`` joint's phase;
the probe plays the trigger by publishing rm_msgs/ActuatorState, as the CAN bridge does.
"""

import math
import sys
import threading

import pytest
import rclpy
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rm_base.host import RobotHost
from rm_base.plugin import PluginInitError
from support.robot import SimRobot
from support.ros import wait_until

from rm_msgs.msg import ActuatorState, GpioCmd, GpioState

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 10.0  # longest wait for a condition [s]; normally met within a few ticks (10 ms)
SLOT = 2.0 * math.pi / 8  # 8 pockets: 0.785 rad per slot

GPIO = {
    'plugins': ['gpio'],
    'gpio.type': 'rm_plugins/UpboardGpio',
    'gpio.rate': 100.0,
    'gpio.backend': 'sim',
    'gpio.inputs': ['ball_switch'],
    'gpio.outputs': ['laser'],
    'gpio.pwm_outputs': ['cover'],
    'gpio.pins.ball_switch.line': 5,
    'gpio.pins.ball_switch.sim_model': 'joint_phase',
    'gpio.pins.ball_switch.sim_joint': 'trigger',
    'gpio.pins.ball_switch.sim_slots': 8,
    'gpio.pins.ball_switch.sim_window': [0.2, 0.5],
    'gpio.pins.laser.line': 6,
    'gpio.pins.cover.pwm_chip': 0,
    'gpio.pins.cover.pwm_channel': 0,
    'gpio.pins.cover.frequency': 50.0,
    'gpio.pins.cover.initial': 0.075,
}


class GpioHarness:
    """rm_robot with the GPIO plugin and a probe node, spun in a background thread."""

    def __init__(self, context, **overrides):
        params = {**GPIO, **overrides}
        self.host = RobotHost(
            context=context,
            parameter_overrides=[Parameter(k, value=v) for k, v in params.items()],
        )
        self.probe = rclpy.create_node('probe', context=context)
        self.states = []
        self._lock = threading.Lock()
        self.probe.create_subscription(GpioState, 'gpio_state', self._on_state, 10)
        self.commands = self.probe.create_publisher(GpioCmd, 'gpio_cmd', 10)
        self.joints = self.probe.create_publisher(ActuatorState, 'actuator_states', 10)
        self.executor = EventsExecutor(context=context)
        self.executor.add_node(self.host)
        self.executor.add_node(self.probe)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _on_state(self, msg):
        with self._lock:
            self.states.append(msg)

    def _spin(self):
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)

    def latest(self):
        with self._lock:
            return self.states[-1] if self.states else None

    def value(self, name):
        msg = self.latest()
        if msg is None or name not in msg.name:
            return None
        return msg.value[list(msg.name).index(name)]

    def values_seen(self, name):
        with self._lock:
            return [m.value[list(m.name).index(name)] for m in self.states]

    def send(self, **values):
        self.commands.publish(GpioCmd(name=list(values), value=[float(v) for v in values.values()]))

    def set_trigger(self, position):
        msg = ActuatorState()
        msg.header.stamp = self.probe.get_clock().now().to_msg()
        msg.name = ['trigger']
        msg.position = [position]
        msg.velocity = [0.0]
        msg.effort = [0.0]
        msg.temperature = [30.0]
        msg.online = [True]
        msg.error_code = [0]
        self.joints.publish(msg)

    def close(self):
        self._stop.set()
        self._thread.join()
        self.host.destroy_node()
        self.probe.destroy_node()
        self.executor.shutdown()


@pytest.fixture
def gpio(ros_context):
    made = []

    def make(**overrides):
        made.append(GpioHarness(ros_context, **overrides))
        return made[-1]

    yield make
    for harness in made:
        harness.close()


def test_the_gpio_plugin_loads_by_name_and_publishes_every_pin(gpio):
    h = gpio()
    assert type(h.host.plugin('gpio')).__module__ == 'rm_plugins.gpio.plugin'
    assert wait_until(lambda: h.latest() is not None, WAIT)
    msg = h.latest()
    assert list(msg.name) == ['ball_switch', 'laser', 'cover']
    assert list(msg.kind) == [GpioState.INPUT, GpioState.OUTPUT, GpioState.PWM]
    assert list(msg.value) == [0.0, 0.0, 0.075]  # switch open (no trigger yet), initials


def test_when_an_output_is_set_expect_it_in_the_state(gpio):
    h = gpio()
    assert wait_until(lambda: h.value('laser') == 0.0, WAIT)
    h.send(laser=1, cover=0.1)
    assert wait_until(lambda: h.value('laser') == 1.0 and h.value('cover') == 0.1, WAIT)


def test_when_a_duty_cycle_is_out_of_range_expect_it_rejected(gpio):
    h = gpio()
    assert wait_until(lambda: h.value('cover') == 0.075, WAIT)
    h.send(cover=1.5)  # rejected: duty above 1
    h.send(cover=-0.2)  # rejected: duty below 0
    h.send(cover=math.nan)  # rejected: NaN
    h.send(laser=1, cover=2.0)  # rejected as a whole: the valid laser entry is not applied
    h.send(cover=0.2)  # the marker: once it shows, every command before it was handled
    assert wait_until(lambda: h.value('cover') == 0.2, WAIT)
    seen = set(h.values_seen('cover'))
    assert seen == {0.075, 0.2}, seen
    assert set(h.values_seen('laser')) == {0.0}


def test_when_the_name_is_unknown_or_an_input_expect_the_command_rejected(gpio):
    h = gpio()
    assert wait_until(lambda: h.value('laser') == 0.0, WAIT)
    h.send(ball_switch=1)  # an input cannot be set
    h.send(buzzer=1)  # no such pin
    h.send(laser=1)  # marker
    assert wait_until(lambda: h.value('laser') == 1.0, WAIT)
    assert set(h.values_seen('ball_switch')) == {0.0}


def test_when_the_trigger_turns_expect_the_simulated_switch_to_toggle(gpio):
    h = gpio()
    # The window is [0.2, 0.5] rad of phase in a 0.785 rad slot: the trigger turning in
    # 0.1 rad steps closes the switch at phases 0.2..0.5 (steps 2..5 of each slot), so
    # 0.0 -> open, 0.3 -> closed, 0.6 -> open, 0.3 + one slot -> closed (the next ball).
    for position, closed in [
        (0.0, 0.0),
        (0.3, 1.0),
        (0.6, 0.0),
        (0.3 + SLOT, 1.0),
        (0.7 + SLOT, 0.0),
    ]:
        h.set_trigger(position)
        assert wait_until(lambda closed=closed: h.value('ball_switch') == closed, WAIT), position


def test_when_disabled_expect_the_outputs_back_at_their_initial_values(gpio):
    h = gpio()
    h.send(laser=1, cover=0.2)
    assert wait_until(lambda: h.value('laser') == 1.0, WAIT)
    h.host.task('gpio').disable('test')
    h.host.task('gpio').enable()
    assert wait_until(lambda: h.value('laser') == 0.0 and h.value('cover') == 0.075, WAIT)


def test_when_the_linux_backend_lacks_gpiod_expect_start_up_to_fail_naming_it(
    ros_context, monkeypatch
):
    monkeypatch.setitem(sys.modules, 'gpiod', None)  # as if not installed
    with pytest.raises(PluginInitError, match=r"plugin 'gpio'.*Python package 'gpiod'"):
        GpioHarness(ros_context, **{'gpio.backend': 'linux'})


def test_when_the_simulated_trigger_turns_expect_the_ball_switch_to_follow():
    # The whole simulated robot (standard.yaml + standard_sim.yaml, gpio only): the sim's
    # trigger motor is turned by hand, the bridge reports it on /actuator_states, and the
    # ball switch (window [0.15, 0.55] rad of phase in a 0.785 rad slot) follows.
    with SimRobot('standard', plugins=['gpio']) as robot:
        robot.subscribe('/gpio_state', GpioState)

        def switch():
            msg = robot.latest('/gpio_state')
            return (
                None if msg is None else dict(zip(msg.name, msg.value, strict=True))['ball_switch']
            )

        def turn_to(angle):
            # In small steps (0.04 rad = 1.44 rad of the 36:1 rotor, under half a rotor turn)
            # so the bridge's encoder unwrapping follows, as it follows a turning motor.
            with robot.world.lock:
                start = robot.world.motor('trigger').model.angle
            steps = max(1, math.ceil(abs(angle - start) / 0.04))
            for i in range(1, steps + 1):
                target = start + (angle - start) * i / steps
                with robot.world.lock:
                    robot.world.motor('trigger').model.reset(angle=target)
                assert robot.wait_until(
                    lambda target=target: abs(robot.joint('trigger')['position'] - target) < 0.01,
                    WAIT,
                )

        for angle, closed in [(0.0, 0.0), (0.3, 1.0), (0.7, 0.0), (0.3 + SLOT, 1.0)]:
            turn_to(angle)
            assert robot.wait_until(lambda closed=closed: switch() == closed, WAIT), angle
