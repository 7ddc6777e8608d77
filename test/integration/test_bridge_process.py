"""can_bridge as a process: params file, SIGINT -> zero frames on the wire, config errors.

rm_sim buses live inside the bridge process, so the wire is read back from the bridge's
own python-can log (``log_file``), which records every frame sent and received.
"""

import pathlib
import uuid

import can
import pytest
import rclpy
from ament_index_python.packages import get_package_prefix
from rclpy.experimental import EventsExecutor
from rm_base.hardware import MODE_MIT, MODE_VELOCITY
from rm_base.hardware.protocols import mit
from rm_base.motors.damiao import protocol as damiao
from rm_base.motors.dji import protocol as dji
from sensor_msgs.msg import JointState
from support.ros import start_process, stop_process, wait_until

from rm_msgs.msg import ActuatorCmd

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

CAN_BRIDGE = pathlib.Path(get_package_prefix('rm_base')) / 'lib' / 'rm_base' / 'can_bridge'
WAIT = 15.0  # longest wait for any condition [s], process start-up included

PARAMS = """\
can_bridge:
  ros__parameters:
    sim: true
    log_file: {log}
    safety:
      # long: a zero on the wire at exit cannot come from the command timeout
      command_timeout_s: 1.0
    buses:
      can0: {{channel: {channel}}}
    joints:
      wheel:
        type: m3508
        bus: can0
        id: 1
        velocity_pid: {{kp: 0.5, ki: 5.0, integral_separation: 3.0, output_limit: 6.0}}
      pitch: {{type: dm4310, bus: can0, id: 2}}
"""


def commands():
    msg = ActuatorCmd()
    msg.name = ['wheel', 'pitch']
    msg.mode = [MODE_VELOCITY, MODE_MIT]
    msg.position = [0.0, 0.3]
    msg.velocity = [20.0, 0.0]
    msg.effort = [0.0, 0.0]
    msg.kp = [0.0, 5.0]
    msg.kd = [0.0, 0.3]
    return msg


def test_sigint_sends_zero_current_and_disable_before_the_bridge_exits(tmp_path, ros_context):
    log = tmp_path / 'frames.log'
    params = tmp_path / 'bridge.yaml'
    params.write_text(PARAMS.format(log=log, channel=f'rm-bridge-proc-{uuid.uuid4().hex[:8]}'))
    bridge = start_process([str(CAN_BRIDGE), '--ros-args', '--params-file', str(params)])
    node = rclpy.create_node('bridge_process_driver', context=ros_context)
    executor = EventsExecutor(context=ros_context)
    executor.add_node(node)
    try:
        pub = node.create_publisher(ActuatorCmd, 'actuator_cmd', 10)
        wheel_velocity = []

        def on_joint_states(msg):
            wheel_velocity.append(msg.velocity[list(msg.name).index('wheel')])

        node.create_subscription(JointState, 'joint_states', on_joint_states, 10)
        node.create_timer(0.02, lambda: pub.publish(commands()))

        def spin(timeout):
            executor.spin_once(timeout_sec=timeout)

        spinning = wait_until(lambda: wheel_velocity and wheel_velocity[-1] > 15.0, WAIT, spin=spin)
        assert spinning, f'no spin: {bridge.poll()=} {wheel_velocity[-3:]}'
        # SIGINT while the last command is still in force (and still being published)
        _, err = stop_process(bridge)
    finally:
        if bridge.poll() is None:
            stop_process(bridge)
        executor.shutdown()
        node.destroy_node()
    assert bridge.returncode == 0, err
    assert 'zero commands sent' in err

    frames = list(can.LogReader(str(log)))
    group = [dji.unpack_command(f.data)[0] for f in frames if f.arbitration_id == 0x200]
    assert any(group), 'the wheel was never driven'
    assert group[-1] == 0  # the last word to the ESC: zero current
    pitch = [bytes(f.data) for f in frames if f.arbitration_id == 0x002]
    limits = damiao.dm_limits('DM4310')
    zero = mit.pack_mit_command(mit.MitCommand(0.0, 0.0, 0.0, 0.0, 0.0), limits)
    assert any(mit.unpack_mit_command(d, limits).kp > 0.0 for d in pitch[:-2] if d != zero)
    # the last two frames to the Damiao: a limp zero command, then DISABLE
    assert pitch[-2:] == [zero, mit.system_frame(mit.SystemCommand.DISABLE)]


def test_config_error_is_one_line_and_exit_status_1():
    bridge = start_process(
        [
            str(CAN_BRIDGE),
            '--ros-args',
            '-p', 'buses.can0.interface:=virtual',
            '-p', 'joints.wheel.type:=m3509',
            '-p', 'joints.wheel.bus:=can0',
            '-p', 'joints.wheel.id:=1',
        ]
    )  # fmt: skip
    _, err = bridge.communicate(timeout=WAIT)
    assert bridge.returncode == 1
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("[can_bridge] configuration error: joints.wheel.type 'm3509'")
    assert 'Traceback' not in err
