"""Bad /actuator_cmd input to a running can_bridge: nothing unsafe may reach the wire.

A sim-mode CanBridgeNode (in-process, private context) drives an M3508 wheel (velocity),
a GM6020 yaw and a DM4310 arm (MIT) on one rm_sim channel; a tap on the channel feeds
every frame to the unsafe-frame checker (reliability.wire), which must find nothing in
any test: no command above a joint's max_effort, none to a joint without a fresh valid
command. NaN, ±inf, unknown modes, unknown joints, negative gains and stale or future
stamps are rejected whole, counted per reason and logged; huge finite values are clamped
to the joint's limits; a 10 kHz flood of good and bad messages changes none of that and
the node keeps running.

Already covered elsewhere and not repeated: length mismatch and unknown joint rejected
whole (test/integration/test_bridge_node.py::test_malformed_commands_are_rejected_whole…),
NaN velocity then recovery (…::test_nan_command_never_reaches_the_motor…), the validation
rules one by one (test/unit/bridge/test_commands.py) and clamping in every mode on a
hand-fed actuator (test/unit/hardware/test_safety.py::test_every_output_is_clamped…).
"""

from __future__ import annotations

import math
import os
import sys
import threading
import time
import uuid

import pytest
import rclpy
from builtin_interfaces.msg import Time
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rm_base.bridge import CanBridgeNode
from rm_base.sim import SimBus
from support.ros import start_process, wait_until

from reliability.wire import WireChecker
from rm_msgs.msg import ActuatorCmd

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 10.0  # [s] longest wait for any condition
GRACE = 0.05  # [s] checker timing grace in real time (CPU steal)
LIMITS = {'wheel': 2.0, 'yaw': 1.2, 'arm': 3.0}  # max_effort [N·m] of each joint

JOINTS = {
    'wheel': {
        'type': 'm3508',
        'id': 1,
        'max_effort': LIMITS['wheel'],
        'velocity_pid': {'kp': 0.5, 'ki': 5.0, 'integral_separation': 3.0, 'output_limit': 6.0},
        'position_pid': {'kp': 10.0},
    },
    'yaw': {
        'type': 'gm6020',
        'id': 1,
        'velocity_pid': {'kp': 0.1, 'ki': 0.5, 'output_limit': 1.2},
        'position_pid': {'kp': 10.0},
    },
    'arm': {'type': 'dm4310', 'id': 3, 'max_effort': LIMITS['arm']},
}


def flat(tree, prefix=''):
    out = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            out.update(flat(value, f'{prefix}{key}.'))
        else:
            out[f'{prefix}{key}'] = value
    return out


def cmd(joint, mode, stamp=None, **values):
    msg = ActuatorCmd()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.name = [joint]
    msg.mode = [mode]
    for field in ('position', 'velocity', 'effort', 'kp', 'kd'):
        setattr(msg, field, [float(values.get(field, 0.0))])
    return msg


class Bridge:
    """A sim can_bridge, a publisher node and a wire tap with the checker."""

    def __init__(self, context) -> None:
        self.channel = f'rm-rel-cmd-{os.getpid()}-{uuid.uuid4().hex[:8]}'
        config = {
            'buses': {'can0': {'interface': 'rm_sim', 'channel': self.channel}},
            'joints': {n: {'bus': 'can0', **j} for n, j in JOINTS.items()},
        }
        params = {'sim': True, 'diagnostics_rate': 20.0, **flat(config)}
        self.node = CanBridgeNode(
            context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()]
        )
        self.world = self.node.sim_world
        # real time: the stall and feedback-window allowances of reliability.rigs.WireWatch
        self.checker = WireChecker(
            config, grace_s=GRACE, record=True, stall_s=0.02, feedback_window_s=0.15
        )
        self.tap = SimBus(self.channel, world=self.world, rx_queue_size=0)
        self.driver = rclpy.create_node('abuse_driver', context=context)
        self.pub = self.driver.create_publisher(ActuatorCmd, 'actuator_cmd', 1000)
        self.executor = EventsExecutor(context=context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.driver)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()
        assert wait_until(lambda: self.pub.get_subscription_count() > 0, WAIT)

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.executor.shutdown()
        self.tap.shutdown()
        self.node.destroy_node()
        self.driver.destroy_node()

    def now(self) -> Time:
        return self.driver.get_clock().now().to_msg()

    def drain(self) -> None:
        while (msg := self.tap.recv(0.0)) is not None:
            self.checker.feed('can0', msg)

    def rejected(self) -> dict[str, int]:
        return self.node.command_stats().rejected

    def publish_for(self, seconds: float, make, rate_hz: float = 200.0) -> None:
        """Publish make() at rate_hz for seconds (stamped now unless make() sets a stamp)."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.pub.publish(make())
            time.sleep(1.0 / rate_hz)
        self.drain()

    def publish_until(self, done, make, rate_hz: float = 200.0) -> bool:
        """Publish make() at rate_hz until done() (at most WAIT seconds); return done()."""
        end = time.monotonic() + WAIT
        while not done() and time.monotonic() < end:
            self.pub.publish(make())
            time.sleep(1.0 / rate_hz)
        self.drain()
        return bool(done())

    def output(self, joint, since):
        """Non-zero commands to joint on the wire after wire time since."""
        self.drain()
        return [e for t, e, nonzero in self.checker.timeline(joint) if t > since and nonzero]

    def assert_safe(self) -> None:
        self.drain()
        assert self.checker.violation_count == 0, '\n'.join(map(str, self.checker.violations))
        assert self.node.hardware.scheduler.stats().errors == 0


@pytest.fixture
def bridge(ros_context):
    b = Bridge(ros_context)
    # every motor is online before the abuse starts
    assert wait_until(lambda: all(s.online for s in b.node.hardware.states()), WAIT)
    yield b
    b.close()


BAD = [
    pytest.param('wheel', {'mode': 2, 'velocity': math.nan}, 'non_finite', id='nan-velocity'),
    pytest.param('wheel', {'mode': 1, 'effort': math.inf}, 'non_finite', id='inf-effort'),
    pytest.param('yaw', {'mode': 3, 'position': -math.inf}, 'non_finite', id='-inf-position'),
    pytest.param('arm', {'mode': 4, 'position': 0.5, 'kp': math.nan}, 'non_finite', id='nan-kp'),
    pytest.param('arm', {'mode': 4, 'kd': math.inf}, 'non_finite', id='inf-kd'),
    pytest.param('wheel', {'mode': 5, 'velocity': 10.0}, 'unknown_mode', id='mode-5'),
    pytest.param('yaw', {'mode': 255, 'effort': 1.0}, 'unknown_mode', id='mode-255'),
    pytest.param('arm', {'mode': 4, 'position': 0.5, 'kp': -5.0}, 'negative_gain', id='kp<0'),
    pytest.param('rotor', {'mode': 1, 'effort': 1.0}, 'unknown_joint', id='unknown-joint'),
]


@pytest.mark.parametrize(('joint', 'values', 'reason'), BAD)
def test_when_a_command_is_invalid_expect_it_rejected_counted_and_nothing_on_the_wire(
    bridge, joint, values, reason
):
    start = bridge.world.timestamp()
    # publish until a few have arrived (under CPU load a 200 Hz stream arrives thinned)
    assert bridge.publish_until(
        lambda: bridge.rejected().get(reason, 0) >= 5, lambda: cmd(joint, **values)
    ), bridge.rejected()
    for name in JOINTS:  # no joint was ever driven: only bad commands came
        assert bridge.output(name, start) == [], name
    assert bridge.node.command_stats().accepted == 0
    assert reason in (bridge.node.command_stats().last_rejection or '')
    bridge.assert_safe()


HUGE = [
    pytest.param('wheel', {'mode': 1, 'effort': 1e12}, id='effort-1e12'),
    pytest.param('wheel', {'mode': 2, 'velocity': -1e9}, id='velocity-1e9'),
    pytest.param('yaw', {'mode': 3, 'position': 1e9}, id='position-1e9'),
    pytest.param('yaw', {'mode': 1, 'effort': -1e300}, id='effort-1e300'),
    pytest.param('arm', {'mode': 4, 'position': 1e6, 'kp': 1e9, 'kd': 1e9}, id='mit-1e9'),
    pytest.param('arm', {'mode': 4, 'effort': 1e12}, id='mit-torque-1e12'),
]


@pytest.mark.parametrize(('joint', 'values'), HUGE)
def test_when_a_value_is_huge_expect_the_output_clamped_to_max_effort(bridge, joint, values):
    start = bridge.world.timestamp()
    bridge.publish_for(0.4, lambda: cmd(joint, **values))
    efforts = [abs(e) for e in bridge.output(joint, start)]
    assert efforts, 'the joint was never driven: a huge value is clamped, not rejected'
    assert max(efforts) <= LIMITS[joint] * 1.05
    if joint == 'wheel':  # current-driven: the frame's effort is exact, and at the clamp
        assert max(efforts) == pytest.approx(LIMITS[joint], rel=0.01)
    bridge.assert_safe()


def test_when_a_command_is_stale_or_from_the_future_expect_it_rejected(bridge):
    start = bridge.world.timestamp()

    def stamped(offset_s):
        t = bridge.driver.get_clock().now().nanoseconds + round(offset_s * 1e9)
        return Time(sec=t // 1_000_000_000, nanosec=t % 1_000_000_000)

    # 5 s old (a replayed or long-delayed message) and 5 s ahead (a sender's clock off)
    old = lambda: cmd('wheel', 1, stamp=stamped(-5.0), effort=1.0)  # noqa: E731
    ahead = lambda: cmd('wheel', 1, stamp=stamped(+5.0), effort=1.0)  # noqa: E731
    assert bridge.publish_until(lambda: bridge.rejected().get('stale', 0) >= 5, old)
    assert bridge.publish_until(lambda: bridge.rejected().get('stale', 0) >= 10, ahead)
    assert bridge.output('wheel', start) == []
    # a fresh stamp is applied
    fresh = bridge.world.timestamp()
    bridge.publish_for(0.3, lambda: cmd('wheel', 1, stamp=stamped(0.0), effort=1.0))
    assert bridge.output('wheel', fresh)
    bridge.assert_safe()


def test_when_a_command_arrives_late_expect_its_timeout_counted_from_its_stamp(bridge):
    # Stamped 70 ms before it is published (a starved sender, a queue): the bridge takes it
    # with 30 ms of its 100 ms timeout left, not another 100 ms from its arrival. (Should
    # the transit itself take > 30 ms on a loaded machine, it is rejected as stale; again.)
    actuator = bridge.node.hardware.actuators['wheel']
    for _ in range(5):
        before, stale = actuator.command, bridge.rejected().get('stale', 0)
        published_ns = time.perf_counter_ns()
        t = bridge.driver.get_clock().now().nanoseconds - 70_000_000
        stamp = Time(sec=t // 1_000_000_000, nanosec=t % 1_000_000_000)
        bridge.pub.publish(cmd('wheel', 1, stamp=stamp, effort=1.0))
        assert wait_until(lambda b=before, n=stale: actuator.command is not b
                          or bridge.rejected().get('stale', 0) > n, WAIT)
        if actuator.command is not before:
            break
    assert actuator.command.stamp_ns <= published_ns - 60_000_000
    bridge.assert_safe()


def test_when_commands_flood_at_10_khz_expect_the_node_alive_and_the_wire_safe(bridge):
    # From another process, as a runaway node would: the flood competes with the bridge
    # for DDS and the executor, not for this process's GIL.
    good = cmd('wheel', 2, velocity=20.0)
    bridge.publish_for(0.3, lambda: good)
    ticks = bridge.node.hardware.scheduler.stats().ticks
    child = start_process([sys.executable, '-m', 'reliability.flood_child', '10000', '3'])
    out, err = child.communicate(timeout=60)
    assert child.returncode == 0, err
    sent, rate = (float(x) for x in out.split()[1::2])
    stats = bridge.node.command_stats()
    print(
        f'flood: {sent:.0f} messages at {rate:.0f}/s; the bridge accepted {stats.accepted}, '
        f'rejected {sum(stats.rejected.values())} {stats.rejected}; scheduler '
        f'{bridge.node.hardware.scheduler.stats()}'
    )
    assert rate > 5000, 'the child could not keep up a flood here'
    assert stats.rejected.get('non_finite', 0) > 0 and stats.rejected.get('unknown_mode', 0) > 0
    # the control loop went on without an error; the node still takes commands
    assert bridge.node.hardware.scheduler.stats().ticks > ticks + 1000
    back = bridge.world.timestamp()
    bridge.publish_for(0.3, lambda: good)
    assert bridge.output('wheel', back)
    bridge.assert_safe()
    for name, limit in LIMITS.items():
        assert bridge.checker.stats(name).max_effort_seen <= limit * 1.05 + 0.01
