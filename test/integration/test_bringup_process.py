"""bringup as a user runs it: the whole robot on rm_sim, a status line, Ctrl-C stops it."""

import os
import pathlib
import signal
import subprocess

import pytest
from ament_index_python.packages import get_package_prefix
from support.ros import call_idempotent, isolate_ros_environment, wait_until

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.realtime]

BRINGUP = pathlib.Path(get_package_prefix('rm_bringup')) / 'lib' / 'rm_bringup' / 'bringup'


def start_bringup(args, stderr_path):
    env = dict(os.environ)
    isolate_ros_environment(env)
    # stderr (the nodes' logs) goes to a file: a pipe nobody reads could fill up and stall
    # the robot while the test waits for its status line on stdout.
    with open(stderr_path, 'w') as stderr:
        return subprocess.Popen(
            [str(BRINGUP), *args], env=env, stdout=subprocess.PIPE, stderr=stderr, text=True
        )


def stop_bringup(proc):
    """SIGINT, as Ctrl-C; SIGKILL if it has not stopped in 30 s."""
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_when_started_on_the_sim_expect_status_lines_and_a_clean_stop_on_sigint(tmp_path):
    log = tmp_path / 'stderr.log'
    # a dump of an earlier run's can_bridge names that run's rm_sim socket, now gone: this
    # run's own plumbing wins over it, where the buses stayed closed before
    dump = tmp_path / 'bridge_dump.yaml'
    dump.write_text('/can_bridge:\n  ros__parameters:\n    buses:\n      can0:\n'
                    '        interface: rm_sim_socket\n        options:\n'
                    '          socket: /tmp/rm_bringup_gone/can.sock\n')
    proc = start_bringup(['--robot', 'standard', '--sim', '--params-file', str(dump)], log)
    lines = []

    def whole(line: str) -> bool:
        # every part: the plugins' states and the bridge's /diagnostics (1 Hz, so a first
        # status line may come before the first diagnostics reached the status view), and
        # every joint heard
        return line.startswith('chassis ') and all(
            part in line for part in ('gimbal ', 'shooter ', 'can0 ', 'offline -')
        )

    def status_seen():
        # Without a terminal the status goes out as a line every 2 s.
        line = proc.stdout.readline()
        if line:
            lines.append(line)
        return any(map(whole, lines)) or proc.poll() is not None

    try:
        # A status line with every part proves both nodes run and talk.
        assert wait_until(status_seen, 60.0, period=0.0), ''.join(lines)
        assert proc.poll() is None, ''.join(lines) + log.read_text()
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = log.read_text()
    assert proc.returncode == 0, err
    assert 'Traceback' not in err, err
    assert err.rstrip().endswith('[bringup] stopped: zero output sent'), err


def test_when_the_robot_is_unknown_expect_one_line_naming_the_installed_ones(tmp_path):
    log = tmp_path / 'stderr.log'
    proc = start_bringup(['--robot', 'nope', '--sim'], log)
    assert proc.wait(timeout=30) == 1
    err = log.read_text().strip().splitlines()
    assert len(err) == 1 and 'installed robots: hero, standard' in err[0], err


def test_when_a_motor_is_taken_offline_in_rm_sim_expect_the_robot_to_see_it(
    tmp_path, ros_context
):
    # bringup --sim runs the motors and the referee in rm_sim, a process of its own; its
    # fault services are rm_sim's, and what they do reaches the robot only through the CAN
    # socket. The referee's reports reach the Referee plugin through a pseudo-terminal.
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_srvs.srv import SetBool

    from rm_msgs.msg import RefereeRobotStatus

    log = tmp_path / 'stderr.log'
    proc = start_bringup(['--robot', 'standard', '--sim'], log)
    node = rclpy.create_node('fault_probe', context=ros_context)
    referee = []
    node.create_subscription(RefereeRobotStatus, '/referee/robot_status', referee.append, 10)
    lines = []

    def status(predicate):
        line = proc.stdout.readline()
        if line:
            lines.append(line)
        return (lines and predicate(lines[-1])) or proc.poll() is not None

    try:
        assert wait_until(lambda: status(lambda s: s.startswith('chassis ')), 60.0, period=0.0)
        assert 'offline -' in lines[-1], lines[-1]
        executor = SingleThreadedExecutor(context=ros_context)
        executor.add_node(node)
        assert wait_until(lambda: executor.spin_once(timeout_sec=0.1) or referee, 20.0)
        # standard_sim.yaml: robot 3 under a 60 W limit and a 100-heat limit
        assert (referee[0].robot_id, referee[0].chassis_power_limit) == (3, 60.0)
        assert referee[0].barrel_heat_limit == 100.0
        client = node.create_client(SetBool, '/rm_sim/wheel_fl/offline')
        assert client.wait_for_service(timeout_sec=20.0)
        response = call_idempotent(executor, client, SetBool.Request(data=True))
        executor.shutdown()
        assert response is not None, 'rm_sim did not answer 4 requests in 20 s'
        assert response.success, response.message
        assert wait_until(lambda: status(lambda s: 'offline wheel_fl' in s), 30.0, period=0.0)
        assert proc.poll() is None, ''.join(lines) + log.read_text()
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)
    finally:
        node.destroy_node()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, log.read_text()


def _children(pid, marker):
    """Pids of the live processes whose parent is pid and whose command line has marker."""
    found = []
    for entry in pathlib.Path('/proc').iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / 'stat').read_text()
            cmdline = (entry / 'cmdline').read_bytes().replace(b'\0', b' ').decode()
        except OSError:
            continue
        fields = stat.rsplit(')', 1)[1].split()
        if int(fields[1]) == pid and marker in cmdline:
            found.append(int(entry.name))
    return found


def _alive(pid):
    try:
        state = pathlib.Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0]
    except OSError:
        return False
    return state not in ('Z', 'X')


def test_when_bringup_is_killed_expect_its_rm_sim_to_stop_too(tmp_path):
    # The finding: kill -9 of bringup left rm_sim running; the next bringup had two
    # /rm_sim nodes and a fault service call could land on the orphan.
    proc = start_bringup(['--robot', 'standard', '--sim'], tmp_path / 'stderr.log')
    sims = []
    try:
        assert wait_until(
            lambda: sims.extend(_children(proc.pid, 'rm_base.bridge.sim_process')) or sims,
            60.0,
        ), (tmp_path / 'stderr.log').read_text()
        proc.kill()  # SIGKILL: no handler of bringup's runs
        proc.wait(timeout=30)
        assert wait_until(lambda: not _alive(sims[0]), 20.0), 'rm_sim outlived bringup'
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for pid in sims:
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)


def test_when_another_robot_runs_in_the_domain_expect_an_error_naming_it(tmp_path, ros_context):
    import rclpy

    log = tmp_path / 'stderr.log'
    other = rclpy.create_node('can_bridge', context=ros_context)  # another robot's bridge
    proc = start_bringup(['--robot', 'standard', '--sim', '--no-status'], log)
    try:
        assert wait_until(lambda: 'another robot runs in ROS domain' in log.read_text()
                          or proc.poll() is not None, 60.0), log.read_text()
        assert 'can_bridge twice' in log.read_text()
        assert proc.poll() is None  # said, not refused: the operator decides
    finally:
        other.destroy_node()
        stop_bringup(proc)
