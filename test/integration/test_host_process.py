"""rm_robot as a process: console script, params file, SIGINT -> zero output, clean exit.

The plugins come from test/fixtures/rm_extra_plugins, installed with colcon into a
temporary prefix whose local_setup.bash is sourced for the child, as a user would.
"""

import pathlib
import shlex
import signal
import time

import pytest
import rclpy
from ament_index_python.packages import get_package_prefix
from fixtures.extra_plugins import install_extra_plugins
from geometry_msgs.msg import TwistStamped
from rclpy.experimental import EventsExecutor
from rm_base.plugin import STATE_QOS
from support.ros import start_process, wait_until

from rm_msgs.msg import ActuatorCmd, PluginState

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

RM_ROBOT = pathlib.Path(get_package_prefix('rm_base')) / 'lib' / 'rm_base' / 'rm_robot'

PARAMS = """\
rm_robot:
  ros__parameters:
    plugins: [echo, counter]
    echo:
      type: rm_extra_plugins/VelocityEcho
      rate: 100.0
      # Long enough that the watchdog cannot be what turns the joints off in this test.
      command_timeout: 1.0
      joints: [left_wheel, right_wheel]
    counter:
      type: rm_extra_plugins/Counter
      rate: 50.0
"""

BAD_PARAMS = """\
rm_robot:
  ros__parameters:
    plugins: [chassis]
    chassis:
      type: rm_extra_plugins/Nope
"""


@pytest.fixture
def extra_plugins(tmp_path_factory):
    return install_extra_plugins(str(tmp_path_factory.getbasetemp()))


def start_rm_robot(install, params_file):
    setup, exe, params = (shlex.quote(str(p)) for p in (install.local_setup, RM_ROBOT, params_file))
    command = f'source {setup} && exec {exe} --ros-args --params-file {params}'
    return start_process(['bash', '-c', command])


def all_off(msg):
    return len(msg.mode) > 0 and all(m == ActuatorCmd.MODE_OFF for m in msg.mode)


def test_sigint_disables_every_plugin_with_zero_output_and_exits_cleanly(
    ros_context, extra_plugins, tmp_path
):
    params_file = tmp_path / 'robot.yaml'
    params_file.write_text(PARAMS)

    probe = rclpy.create_node('probe', context=ros_context)
    cmds, states = [], []
    probe.create_subscription(ActuatorCmd, '/actuator_cmd', cmds.append, 10)
    probe.create_subscription(PluginState, '/rm_robot/echo/state', states.append, STATE_QOS)
    command_pub = probe.create_publisher(TwistStamped, '/echo_cmd', 10)
    executor = EventsExecutor(context=ros_context)
    executor.add_node(probe)

    def command_and_spin(timeout):
        msg = TwistStamped()
        msg.header.stamp = probe.get_clock().now().to_msg()
        msg.twist.linear.x = 0.5
        command_pub.publish(msg)
        executor.spin_once(timeout_sec=timeout)

    proc = start_rm_robot(extra_plugins, params_file)
    try:
        # Running: the plugin loaded by name follows our command.
        # The state (latched, another topic) may arrive after the first command: wait for both.
        assert wait_until(
            lambda: cmds and list(cmds[-1].velocity) == [0.5, 0.5]
            and any(s.state_name == 'TRACKING' for s in states), 20.0,
            spin=command_and_spin, period=0.02,
        ), proc.stderr.read() if proc.poll() is not None else 'rm_robot did not follow'

        # Commands keep coming while rm_robot shuts down: any OFF now is the shutdown's.
        before = len(cmds)
        proc.send_signal(signal.SIGINT)
        assert wait_until(lambda: proc.poll() is not None, 15.0, spin=command_and_spin, period=0.02)
        deadline = time.monotonic() + 2.0  # let in-flight messages arrive
        wait_until(lambda: any(all_off(m) for m in cmds[before:]), 2.0, spin=command_and_spin)
        while time.monotonic() < deadline and not all_off(cmds[-1]):
            executor.spin_once(timeout_sec=0.05)
    finally:
        if proc.poll() is None:
            proc.kill()
        _, stderr = proc.communicate(timeout=10)
        executor.shutdown()
        probe.destroy_node()

    assert proc.returncode == 0, stderr
    assert 'Traceback' not in stderr, stderr
    offs = [m for m in cmds[before:] if all_off(m)]
    assert offs, 'no zero output after SIGINT'
    assert list(offs[-1].name) == ['left_wheel', 'right_wheel']
    assert all_off(cmds[-1]), 'a non-zero command came after the zero output'
    assert 'echo' in stderr and 'shutting down' in stderr  # the transition is logged


def test_an_unknown_plugin_type_exits_1_with_one_clear_line(extra_plugins, tmp_path):
    params_file = tmp_path / 'bad.yaml'
    params_file.write_text(BAD_PARAMS)
    proc = start_rm_robot(extra_plugins, params_file)
    _, stderr = proc.communicate(timeout=30)
    assert proc.returncode == 1, stderr
    assert 'Traceback' not in stderr, stderr
    errors = [line for line in stderr.splitlines() if 'configuration error' in line]
    assert len(errors) == 1, stderr
    assert errors[0].startswith(
        "[rm_robot] configuration error: plugin 'chassis': unknown plugin type "
        "'rm_extra_plugins/Nope'; available: "
    )
    assert 'rm_extra_plugins/Counter' in errors[0]
