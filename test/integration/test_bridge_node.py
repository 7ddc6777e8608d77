"""can_bridge in-process on rm_sim: commands, states, diagnostics, services, and safety.

Why one module: every test shares the bridge-and-driver fixture; they are one feature, the
node.

Each test builds a CanBridgeNode in a private Context with ``sim: true`` on a channel of
its own, plus a driver node that publishes /actuator_cmd at 100 Hz and keeps the latest
/joint_states, /actuator_states and /diagnostics; one EventsExecutor spins both in a
background thread (as main() does: spin_once in a loop). The bridge's world runs in real
time, so the tests wait on conditions (WAIT seconds at most, normally well under one).

What reaches the motor is read off the wire: a second rm_sim bus on the bridge's channel
receives every 0x200 group frame the bridge sends, and the wheel's slot is decoded.
"""

import math
import os
import threading
import time
import uuid

import can
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rm_base.bridge import CanBridgeNode
from rm_base.bridge import node as bridge_node
from rm_base.errors import ConfigError
from rm_base.hardware import MODE_OFF, MODE_VELOCITY
from rm_base.motors.dji import protocol as dji
from rm_base.sim import Fault, SimBus, Timing, find_channel
from sensor_msgs.msg import JointState
from std_srvs.srv import SetBool
from support.ros import wait_until

from rm_msgs.msg import ActuatorCmd, ActuatorState, CanFrame

pytestmark = [pytest.mark.ros, pytest.mark.realtime]

WAIT = 10.0  # longest wait for any condition [s]
TARGET = 20.0  # wheel velocity target [rad/s], well inside the M3508's 50 rad/s
ZERO_RUN = 30  # consecutive zero-current frames (30 ms at 1 kHz) that count as "zero"
STALL_TIMEOUT = 0.5  # the rig's feedback and command timeouts [s] (the bridge's: 0.1)

WHEEL_PID = {
    'joints.wheel.velocity_pid.kp': 0.5,
    'joints.wheel.velocity_pid.ki': 5.0,
    'joints.wheel.velocity_pid.integral_separation': 3.0,
    'joints.wheel.velocity_pid.output_limit': 6.0,
}


def wheel(name='wheel', esc_id=1):
    return {
        f'joints.{name}.type': 'm3508',
        f'joints.{name}.bus': 'can0',
        f'joints.{name}.id': esc_id,
    }


def velocity_cmd(targets):
    """ActuatorCmd with MODE_VELOCITY for {joint: velocity}."""
    msg = ActuatorCmd()
    msg.name = list(targets)
    msg.mode = [MODE_VELOCITY] * len(targets)
    msg.velocity = [float(v) for v in targets.values()]
    for field in ('position', 'effort', 'kp', 'kd'):
        setattr(msg, field, [0.0] * len(targets))
    return msg


class Rig:
    """A sim-mode bridge, a driver node and a wire tap on the bridge's channel."""

    def __init__(self, context, params):
        self.channel = f'rm-bridge-{os.getpid()}-{uuid.uuid4().hex[:8]}'
        overrides = {
            'sim': True,
            'buses.can0.channel': self.channel,
            'diagnostics_rate': 20.0,
            # A stall of the whole VM (CPU steal) longer than a timeout rightly holds the
            # wheel at zero for a few ticks; tests that judge a timeout set it themselves.
            'safety.feedback_timeout_s': STALL_TIMEOUT,
            'safety.command_timeout_s': STALL_TIMEOUT,
            **wheel(),
            **WHEEL_PID,
            **params,
        }
        self.bridge = CanBridgeNode(
            context=context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )
        self.world = self.bridge.sim_world
        self.driver = rclpy.create_node('bridge_test_driver', context=context)
        self.cmd_pub = self.driver.create_publisher(ActuatorCmd, 'actuator_cmd', 10)
        #: The message the driver publishes every 10 ms (None: nothing).
        self.command = None
        self.driver.create_timer(0.01, self._publish_command)
        self.latest = {}
        for cls, topic in (
            (JointState, 'joint_states'),
            (ActuatorState, 'actuator_states'),
            (DiagnosticArray, '/diagnostics'),
        ):
            self.driver.create_subscription(
                cls, topic, lambda msg, t=topic: self.latest.__setitem__(t, msg), 10
            )
        # every 0x200 frame on the wire; unbounded queue, drained by wheel_currents()
        self.tap = SimBus(
            self.channel,
            world=self.world,
            rx_queue_size=0,
            can_filters=[{'can_id': 0x200, 'can_mask': 0x7FF}],
        )
        self.currents = []
        self.executor = EventsExecutor(context=context)
        self.executor.add_node(self.bridge)
        self.executor.add_node(self.driver)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()
        assert wait_until(lambda: self.cmd_pub.get_subscription_count() > 0, WAIT)

    def _spin(self):
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.05)

    def _publish_command(self):
        if self.command is not None:
            self.cmd_pub.publish(self.command)

    def close(self):
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.executor.shutdown()
        self.tap.shutdown()
        self.bridge.destroy_node()
        self.driver.destroy_node()

    # --- observations ---
    def wheel_currents(self, slot=0):
        """Raw currents of one slot of every 0x200 frame seen so far, oldest first."""
        while (frame := self.tap.recv(0.0)) is not None:
            self.currents.append(dji.unpack_command(frame.data)[slot])
        return self.currents

    def wire_is_zero(self):
        """The last ZERO_RUN frames on the wire command zero current."""
        recent = self.wheel_currents()[-ZERO_RUN:]
        return len(recent) == ZERO_RUN and not any(recent)

    def wire_drives(self):
        """The last frames on the wire command current (the motor is driven)."""
        recent = self.wheel_currents()[-5:]
        return len(recent) == 5 and all(recent)

    def state(self, name='wheel'):
        """The joint's fields in the latest /actuator_states (waits for the first one).

        The bridge sees this test's subscription some time after it is made (discovery),
        so the first states can come after the first frames on the wire.
        """
        assert wait_until(lambda: 'actuator_states' in self.latest, WAIT), 'no actuator_states'
        msg = self.latest['actuator_states']
        i = list(msg.name).index(name)
        return {
            field: getattr(msg, field)[i]
            for field in (
                'position',
                'velocity',
                'effort',
                'temperature',
                'online',
                'error_code',
                'mode',
                'command',
            )
        }

    def spinning(self, name='wheel', target=TARGET):
        msg = self.latest.get('joint_states')
        if msg is None:
            return False
        velocity = msg.velocity[list(msg.name).index(name)]
        return abs(velocity - target) < 0.05 * abs(target)

    def status(self, name):
        msg = self.latest.get('/diagnostics')
        if msg is None:
            return None
        return next((s for s in msg.status if s.name == f'can_bridge: {name}'), None)

    def values(self, name):
        status = self.status(name)
        return {} if status is None else {kv.key: kv.value for kv in status.values}

    def hold(self, reason):
        status = self.status('joint wheel')
        return status is not None and self.values('joint wheel')['hold_reason'] == reason

    def held_safe(self):
        """/actuator_states shows the wheel held: MODE_OFF and zero command."""
        s = self.state()
        return s['mode'] == MODE_OFF and s['command'] == 0.0

    def spin_up(self):
        self.command = velocity_cmd({'wheel': TARGET})
        assert wait_until(lambda: self.spinning() and self.wire_drives(), WAIT), (
            self.latest.get('joint_states'),
            self.wheel_currents()[-20:],
        )


@pytest.fixture
def make_rig(ros_context):
    rigs = []

    def make(**params):
        rig = Rig(ros_context, params)
        rigs.append(rig)
        return rig

    yield make
    for rig in rigs:
        rig.close()


# --- commands and states --------------------------------------------------------------------


def test_velocity_command_spins_the_motor(make_rig):
    rig = make_rig()
    rig.command = velocity_cmd({'wheel': TARGET})
    # the simulated motor itself turns at the commanded output-shaft speed
    assert wait_until(
        lambda: (
            rig.spinning()
            and rig.wire_drives()
            and rig.world.motor('wheel').model.velocity == pytest.approx(TARGET, rel=0.05)
        ),
        WAIT,
    ), rig.latest.get('joint_states')


def test_messages_of_several_plugins_each_drive_their_own_joints(make_rig):
    other_pid = {k.replace('.wheel.', '.other.'): v for k, v in WHEEL_PID.items()}
    rig = make_rig(**wheel('other', 2), **other_pid)
    chassis, other = velocity_cmd({'wheel': TARGET}), velocity_cmd({'other': -10.0})
    other_pub = rig.driver.create_publisher(ActuatorCmd, 'actuator_cmd', 10)
    rig.driver.create_timer(0.01, lambda: other_pub.publish(other))
    rig.command = chassis
    assert wait_until(lambda: rig.spinning() and rig.spinning('other', -10.0), WAIT)


def test_actuator_states_carry_every_field(make_rig):
    rig = make_rig()
    rig.spin_up()
    first = rig.state()
    assert wait_until(lambda: rig.state()['position'] > first['position'] + 1.0, WAIT)
    s = rig.state()
    assert s['online'] is True
    assert s['mode'] == MODE_VELOCITY
    assert s['velocity'] == pytest.approx(TARGET, rel=0.05)
    # friction needs a forward effort: viscous 2.5e-3 N·m·s/rad x 20 rad/s + 0.1 N·m Coulomb
    assert 0.05 < s['command'] < 1.0
    assert 0.0 < s['effort'] < 1.0
    assert s['temperature'] == pytest.approx(25.0, abs=2.0)  # ambient, C620 reports °C
    assert s['error_code'] == 0
    names = list(rig.latest['joint_states'].name)
    assert names == ['wheel']


def test_states_nobody_subscribes_are_not_built_and_the_next_subscriber_gets_them(
    make_rig, monkeypatch
):
    built = []
    for builder in ('actuator_state_msg', 'state_msgs'):
        original = getattr(bridge_node, builder)
        monkeypatch.setattr(
            bridge_node, builder, lambda *a, b=builder, f=original: built.append(b) or f(*a)
        )
    rig = make_rig()
    for sub in list(rig.driver.subscriptions):
        if sub.topic_name in ('/joint_states', '/actuator_states'):
            rig.driver.destroy_subscription(sub)
    pub = rig.bridge._joint_states_pub
    assert wait_until(lambda: pub.get_subscription_count() == 0, WAIT)
    unheard = rig.bridge.states_unheard
    assert wait_until(lambda: rig.bridge.states_unheard > unheard + 10, WAIT)
    got = []
    rig.driver.create_subscription(JointState, 'joint_states', got.append, 10)
    built.clear()
    assert wait_until(lambda: len(got) >= 3, WAIT)
    assert list(got[-1].name) == ['wheel']
    assert built == []  # /actuator_states has still nobody: only JointState is built


def test_diagnostics_report_joints_bus_scheduler_commands_inbox_and_simulator(make_rig):
    rig = make_rig()
    rig.spin_up()
    # a report from after the first 100 ms of running
    assert wait_until(lambda: int(rig.values('scheduler').get('ticks', '0')) > 100, WAIT)
    joint = rig.status('joint wheel')
    assert joint.level == DiagnosticStatus.OK and joint.message == 'driven (VELOCITY)'
    assert joint.hardware_id == 'can0 m3508 id 1'
    assert rig.values('joint wheel')['online'] == 'True'
    bus = rig.status('bus can0')
    assert (bus.level, bus.message) == (DiagnosticStatus.OK, 'up')
    bus_values = rig.values('bus can0')
    # 0x200 out and 0x201 back each millisecond: ~2 x 111 bits x 1000/s = ~22 % of 1 Mbit/s
    assert 10.0 < float(bus_values['load [%]']) < 40.0
    assert int(bus_values['frames_sent']) > 0 and int(bus_values['frames_received']) > 0
    scheduler = rig.values('scheduler')
    assert float(scheduler['rate [Hz]']) == 1000.0
    assert 'period_error_max [us]' in scheduler
    assert int(rig.values('commands')['accepted']) > 0
    inbox = rig.values('inbox')  # /actuator_cmd as the bridge's inbox took it
    assert int(inbox['/actuator_cmd taken']) > 0 and inbox['/actuator_cmd dropped'] == '0'
    simulator = rig.values('simulator')  # the real-time world's clock, next to the loop's
    assert float(simulator['time [s]']) > 0.1 and 'slipped [s]' in simulator


def test_malformed_commands_are_rejected_whole_and_counted(make_rig):
    rig = make_rig()
    bad = velocity_cmd({'wheel': TARGET})
    bad.kd = [0.0, 0.0]  # two gains for one joint
    unknown = velocity_cmd({'wheel': TARGET, 'rear': 1.0})
    for msg in (bad, unknown):
        rig.cmd_pub.publish(msg)

    def counted():
        rejected = rig.bridge.command_stats().rejected
        return rejected == {'length_mismatch': 1, 'unknown_joint': 1}

    assert wait_until(counted, WAIT), rig.bridge.command_stats()
    assert wait_until(lambda: rig.values('commands').get('rejected') == '2', WAIT)
    # the valid entry of the unknown-joint message never reached the wheel
    assert wait_until(lambda: len(rig.wheel_currents()) >= ZERO_RUN, WAIT)
    assert not any(rig.wheel_currents())
    assert rig.state()['mode'] == MODE_OFF
    assert rig.bridge.command_stats().accepted == 0


def test_targets_computed_from_another_bridges_states_are_refused(make_rig):
    # rm_robot echoes the stamp of the states its targets came from: after a restart of
    # the bridge, a position computed against the old bridge's encoders is refused.
    rig = make_rig()
    rig.state()  # the first /actuator_states reached the driver
    first = rig.latest['actuator_states'].header.stamp
    old = velocity_cmd({'wheel': TARGET})
    old.states_stamp.sec, old.states_stamp.nanosec = first.sec - 1, first.nanosec
    rig.command = old
    assert wait_until(lambda: rig.bridge.command_stats().rejected.get('old_states', 0) >= 3, WAIT)
    assert wait_until(lambda: len(rig.wheel_currents()) >= ZERO_RUN, WAIT)
    assert not any(rig.wheel_currents()) and rig.bridge.command_stats().accepted == 0
    assert 'older than this bridge' in rig.bridge.command_stats().last_rejection
    own = velocity_cmd({'wheel': TARGET})
    own.states_stamp = rig.latest['actuator_states'].header.stamp
    rig.command = own
    assert wait_until(rig.spinning, WAIT), rig.bridge.command_stats()


def test_start_up_parameters_cannot_be_changed_at_run_time(make_rig):
    rig = make_rig()
    typed, hardware = rig.bridge.set_parameters(
        [Parameter('publish_rate', value=50.0), Parameter('joints.wheel.id', value=2)]
    )
    assert not typed.successful and 'read-only' in typed.reason
    assert not hardware.successful
    assert hardware.reason.startswith(
        'joints.wheel.id: read at start-up: a change needs a restart'), hardware.reason
    assert rig.bridge.get_parameter('publish_rate').value == 200.0
    assert rig.bridge.get_parameter('joints.wheel.id').value == 1


def test_frames_topic_shows_commands_sent_and_feedback_received(make_rig):
    rig = make_rig(publish_frames=True)
    frames = []
    rig.driver.create_subscription(CanFrame, '/can_bridge/frames', frames.append, 100)
    rig.spin_up()
    assert wait_until(
        lambda: {(f.id, f.is_rx) for f in frames} >= {(0x200, False), (0x201, True)}, WAIT
    )
    sent = next(f for f in frames if f.id == 0x200)
    assert sent.bus == 'can0' and len(sent.data) == 8


def test_sim_services_inject_and_clear_faults(make_rig):
    rig = make_rig()
    client = rig.driver.create_client(SetBool, '/can_bridge/sim/wheel/offline')
    bus_off = rig.driver.create_client(SetBool, '/can_bridge/sim/can0/bus_off')
    assert client.wait_for_service(timeout_sec=WAIT) and bus_off.wait_for_service(timeout_sec=WAIT)

    def call(cli, data):
        future = cli.call_async(SetBool.Request(data=data))
        assert wait_until(future.done, WAIT)
        return future.result()

    response = call(client, True)
    assert response.success and response.message == 'wheel: offline injected'
    assert wait_until(lambda: not rig.state()['online'], WAIT)
    assert call(client, False).success
    assert wait_until(lambda: rig.state()['online'], WAIT)
    assert call(bus_off, True).message == 'can0: bus-off injected'
    assert rig.world.channel(rig.channel).state is can.BusState.ERROR
    assert call(bus_off, False).success
    assert rig.world.channel(rig.channel).state is can.BusState.ACTIVE


def test_config_error_names_the_key_and_leaves_nothing_behind(ros_context):
    channel = f'rm-bridge-bad-{uuid.uuid4().hex[:8]}'
    # the world builds (the simulator ignores the key), then the hardware layer refuses it
    params = {'sim': True, 'buses.can0.channel': channel, **wheel(), 'joints.wheel.gain': 1.0}
    overrides = [Parameter(k, value=v) for k, v in params.items()]
    with pytest.raises(ConfigError, match=r"joints\.wheel: unknown key\(s\) \['gain'\]"):
        CanBridgeNode(context=ros_context, parameter_overrides=overrides)
    # the simulated world was closed again: its channel name is free
    assert find_channel(channel) is None


def test_wrong_parameter_type_names_the_parameter(ros_context):
    overrides = [
        Parameter('publish_rate', value='fast'),
        *(Parameter(k, value=v) for k, v in wheel().items()),
    ]
    with pytest.raises(ConfigError, match=r"parameter 'publish_rate' must be double \[Hz\]"):
        CanBridgeNode(context=ros_context, parameter_overrides=overrides)


def test_sim_world_error_is_a_config_error_naming_the_group(ros_context):
    params = {
        'sim': True,
        'buses.can0.channel': f'rm-bridge-bad-{uuid.uuid4().hex[:8]}',
        **wheel(),
        'sim.body.gimbal.yaw.motor': 'yaw',  # no joint of that name
    }
    overrides = [Parameter(k, value=v) for k, v in params.items()]
    message = r"simulated world .*gimbal\.yaw\.motor is 'yaw', which is not a configured motor"
    with pytest.raises(ConfigError, match=message):
        CanBridgeNode(context=ros_context, parameter_overrides=overrides)


SIM_YAML = """\
can_bridge:
  ros__parameters:
    sim: true
    {sim_group}
    buses:
      can0: {{channel: {channel}}}
    joints:
      wheel: {{type: m3508, bus: can0, id: 1}}
      yaw: {{type: gm6020, bus: can0, id: 1, sim: {{load_inertia: 0.02}}}}
"""

DOTTED_GROUP = """sim.timing: stepped
    sim.body:
      gimbal: {yaw: {motor: yaw}}
    sim.imu: {path: '${RM_TEST_BRIDGE_IMU}', mount: gimbal, rate_hz: 100.0}"""

NESTED_GROUP = """sim:
      timing: stepped"""


def bridge_from_file(context, path):
    return CanBridgeNode(context=context, cli_args=['--ros-args', '--params-file', str(path)])


def test_a_params_file_with_the_dotted_sim_group_builds_body_and_imu(
    ros_context, tmp_path, monkeypatch
):
    monkeypatch.setenv('RM_TEST_BRIDGE_IMU', str(tmp_path / 'imu'))
    channel = f'rm-bridge-yaml-{uuid.uuid4().hex[:8]}'
    path = tmp_path / 'bridge.yaml'
    path.write_text(SIM_YAML.format(sim_group=DOTTED_GROUP, channel=channel))
    bridge = bridge_from_file(ros_context, path)
    try:
        world = bridge.sim_world
        assert world.timing is Timing.STEPPED
        assert world.body.yaw_joint.device is world.motor('yaw')
        assert world.motor('yaw').model.params.load_inertia == 0.02
        assert world.imu().path == str(tmp_path / 'imu')
        assert (tmp_path / 'imu').is_symlink()
    finally:
        bridge.destroy_node()


def test_a_params_file_with_sim_twice_gets_a_hint_not_a_type_error(ros_context, tmp_path):
    path = tmp_path / 'bridge.yaml'
    path.write_text(SIM_YAML.format(sim_group=NESTED_GROUP, channel='unused'))
    with pytest.raises(ConfigError, match=r"the params file has the key 'sim' twice"):
        bridge_from_file(ros_context, path)


def test_stepped_world_moves_only_when_stepped(ros_context):
    params = {
        'sim': True,
        'sim.timing': 'stepped',
        'buses.can0.channel': f'rm-bridge-stepped-{uuid.uuid4().hex[:8]}',
        **wheel(),
    }
    bridge = CanBridgeNode(
        context=ros_context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()]
    )
    try:
        world = bridge.sim_world
        assert world.timing is Timing.STEPPED and not world.running
        assert not bridge.hardware.scheduler.running  # the loop runs only in step()
        actuator = bridge.hardware.actuators['wheel']
        assert actuator.feedback is None  # a motor sends feedback only when the world ticks
        bridge.step(5)
        assert world.time_ns == 5 * 1_000_000
        assert bridge.hardware.scheduler.stats().ticks == 5
        # the feedback sent at a tick is taken by the loop tick right after it
        assert actuator.feedback is not None
        assert actuator.feedback.stamp_ns == 5 * 1_000_000
    finally:
        bridge.destroy_node()


def test_when_stepped_with_a_command_expect_the_same_wheel_speeds_on_every_run(ros_context):
    def run(tag):
        params = {
            'sim': True,
            'sim.timing': 'stepped',
            'buses.can0.channel': f'rm-bridge-lockstep-{tag}-{uuid.uuid4().hex[:8]}',
            **wheel(),
            # the standard robot's wheel loop (rm_bringup/config/standard.yaml)
            'joints.wheel.velocity_pid.kp': 0.6,
            'joints.wheel.velocity_pid.ki': 4.0,
            'joints.wheel.velocity_pid.output_limit': 4.0,
        }
        bridge = CanBridgeNode(
            context=ros_context,
            parameter_overrides=[Parameter(k, value=v) for k, v in params.items()],
        )
        try:
            speeds = []
            for _ in range(200):
                bridge.hardware.set_command('wheel', 2, velocity=10.0)  # MODE_VELOCITY
                bridge.step(1)
                speeds.append(bridge.hardware.actuators['wheel'].state().velocity)
            return speeds
        finally:
            bridge.destroy_node()

    first, second = run('a'), run('b')
    assert first[-1] > 5.0  # [rad/s] on its way to 10 rad/s within 0.2 s
    assert first == second  # bit for bit: nothing depends on the machine's timing


# --- safety: every fault ends with zero current on the wire, and the node runs on -----------


def test_motor_offline_zeroes_the_wire_and_control_resumes_when_it_is_back(make_rig):
    rig = make_rig()
    rig.spin_up()
    rig.world.inject('wheel', Fault.offline())
    assert wait_until(rig.wire_is_zero, WAIT), rig.wheel_currents()[-ZERO_RUN:]
    assert wait_until(lambda: rig.held_safe() and not rig.state()['online'], WAIT)
    assert wait_until(lambda: rig.hold('offline'), WAIT)
    assert rig.status('joint wheel').level == DiagnosticStatus.ERROR
    assert rig.status('joint wheel').message == 'held at zero: offline'
    rig.world.clear_faults('wheel')
    assert wait_until(lambda: rig.spinning() and rig.wire_drives(), WAIT)


def test_over_temperature_zeroes_the_wire_until_the_motor_cools(make_rig):
    rig = make_rig()
    rig.spin_up()
    rig.world.inject('wheel', Fault.over_temperature(130.0))  # limit 80 °C (M3508 default)
    assert wait_until(rig.wire_is_zero, WAIT), rig.wheel_currents()[-ZERO_RUN:]
    assert wait_until(lambda: rig.held_safe() and rig.state()['temperature'] == 130.0, WAIT)
    assert rig.state()['online']
    assert wait_until(lambda: rig.hold('over_temperature'), WAIT)
    assert rig.status('joint wheel').level == DiagnosticStatus.ERROR
    # below limit - hysteresis (80 - 5 °C) the joint resumes; the node never stopped
    rig.world.inject('wheel', Fault.over_temperature(60.0))
    assert wait_until(lambda: rig.spinning() and rig.wire_drives(), WAIT)


def test_command_timeout_zeroes_the_wire_and_a_fresh_command_resumes(make_rig):
    rig = make_rig(**{'safety.command_timeout_s': 0.1})  # the bridge's default
    rig.spin_up()
    rig.command = None  # the plugin stops publishing
    assert wait_until(rig.wire_is_zero, WAIT), rig.wheel_currents()[-ZERO_RUN:]
    assert wait_until(lambda: rig.held_safe() and rig.hold('command_timeout'), WAIT)
    assert rig.state()['online']
    assert rig.status('joint wheel').level == DiagnosticStatus.WARN
    rig.command = velocity_cmd({'wheel': TARGET})
    assert wait_until(lambda: rig.wire_drives() and rig.spinning(), WAIT)


def test_nan_command_never_reaches_the_motor_and_the_joint_times_out_to_zero(make_rig):
    rig = make_rig(**{'safety.command_timeout_s': 0.1})
    rig.spin_up()
    rig.command = velocity_cmd({'wheel': math.nan})
    # the last valid target stays in force only until the command timeout (0.1 s)
    assert wait_until(rig.wire_is_zero, WAIT), rig.wheel_currents()[-ZERO_RUN:]
    assert wait_until(lambda: rig.held_safe() and rig.hold('command_timeout'), WAIT)
    assert rig.bridge.command_stats().rejected['non_finite'] > 0
    assert wait_until(lambda: rig.values('commands').get('rejected non_finite', '0') != '0', WAIT)
    assert 'velocity is not a finite number: nan' in rig.values('commands')['last_rejection']
    rig.command = velocity_cmd({'wheel': TARGET})
    assert wait_until(lambda: rig.wire_drives() and rig.spinning(), WAIT)


def test_bus_error_recovers_with_zero_output_until_a_fresh_command(make_rig):
    rig = make_rig(**{'buses.can0.reconnect_initial_s': 0.05})
    rig.spin_up()
    channel = rig.world.channel(rig.channel)
    channel.set_state(can.BusState.ERROR)  # bus-off: nothing moves either way
    assert wait_until(lambda: rig.values('bus can0').get('reopen_count', '0') != '0', WAIT)
    assert wait_until(lambda: not rig.state()['online'] and rig.held_safe(), WAIT)
    # The plugin stops too. A reopen while the bus is still off counts as a recovery, and a
    # command after it is fresh; so wait until the last command is stale on any reading.
    rig.command = None
    hw = rig.bridge.hardware
    timeout_ns = hw.config.safety.command_timeout_s * 1e9
    assert wait_until(
        lambda: time.perf_counter_ns() - hw.actuators['wheel'].command.stamp_ns > 2 * timeout_ns,
        WAIT,
    )
    reopens = int(rig.values('bus can0')['reopen_count'])
    frames_before = len(rig.wheel_currents())
    channel.set_state(can.BusState.ACTIVE)
    # back: frames flow again, and they command zero until a fresh command
    assert wait_until(lambda: len(rig.wheel_currents()) > frames_before + ZERO_RUN, WAIT)
    assert rig.wire_is_zero()
    assert wait_until(lambda: rig.state()['online'] and rig.held_safe(), WAIT)
    assert wait_until(lambda: rig.values('bus can0')['state'] == 'up', WAIT)
    assert int(rig.values('bus can0')['reopen_count']) >= reopens
    rig.command = velocity_cmd({'wheel': TARGET})
    assert wait_until(lambda: rig.wire_drives() and rig.spinning(), WAIT)


def test_when_the_simulator_runs_in_real_time_expect_step_refused(ros_context):
    params = {
        'sim': True,
        'buses.can0.channel': f'rm-bridge-realtime-{uuid.uuid4().hex[:8]}',
        **wheel(),
    }
    bridge = CanBridgeNode(
        context=ros_context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()]
    )
    try:
        with pytest.raises(ConfigError, match=r'step\(\) needs sim: true and sim.timing: stepped'):
            bridge.step()
    finally:
        bridge.destroy_node()
