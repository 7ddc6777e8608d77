"""rmcli topic pub/echo/list/hz in child processes against a test node (private domain)."""

import signal
import sys
import threading
import time

import pytest
import yaml
from std_msgs.msg import String
from support.ros import start_process, stop_process, wait_until

from rm_msgs.msg import ChassisCmd

pytestmark = pytest.mark.ros

TIMEOUT_S = 30.0  # discovery is ~0.4 s on a quiet machine; far more under CPU steal


def rmcli(*args):
    return start_process([sys.executable, '-m', 'rm_bringup.cli', *args])


def finish(proc):
    out, err = proc.communicate(timeout=TIMEOUT_S)
    return proc.returncode, out, err


def test_pub_once_with_a_mode_name_reaches_a_subscriber(test_node):
    node, executor = test_node
    received = []
    node.create_subscription(ChassisCmd, '/chassis_cmd', received.append, 10)
    proc = rmcli('topic', 'pub', '--once', '/chassis_cmd', 'rm_msgs/msg/ChassisCmd', '{mode: GYRO}')
    try:
        # pub --once waits for the subscription before publishing, so nothing is lost.
        arrived = wait_until(lambda: received, TIMEOUT_S, spin=executor.spin_once)
    finally:
        code, out, err = finish(proc)
    assert arrived, f'nothing received; rmcli said:\n{out}\n{err}'
    assert code == 0, err
    assert received[0].mode == ChassisCmd.GYRO == 4
    wait_until(lambda: False, 0.3, spin=executor.spin_once)  # a second message would be here now
    assert len(received) == 1


def test_pub_takes_the_type_from_the_graph_and_stamps_header_auto(test_node):
    node, executor = test_node
    received = []
    node.create_subscription(ChassisCmd, '/cli_test/inferred', received.append, 10)
    proc = rmcli(
        'topic',
        'pub',
        '-1',
        '--discovery-timeout',
        str(TIMEOUT_S),
        '/cli_test/inferred',
        '{header: auto, mode: twist, power_limit: 80}',
    )
    try:
        arrived = wait_until(lambda: received, TIMEOUT_S, spin=executor.spin_once)
    finally:
        code, out, err = finish(proc)
    assert arrived and code == 0, f'{out}\n{err}'
    msg = received[0]
    assert (msg.mode, msg.power_limit) == (ChassisCmd.TWIST, 80.0)
    stamp_s = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
    assert abs(stamp_s - time.time()) < 60.0  # stamped now, not left at 0


def test_pub_times_publishes_that_many_messages(test_node):
    node, executor = test_node
    received = []
    node.create_subscription(String, '/cli_test/times', received.append, 10)
    proc = rmcli(
        'topic',
        'pub',
        '-t',
        '3',
        '-r',
        '20',
        '-p',
        '0',
        '/cli_test/times',
        'std_msgs/msg/String',
        'data: hi',
    )
    try:
        wait_until(lambda: proc.poll() is not None, TIMEOUT_S, spin=executor.spin_once)
        wait_until(lambda: len(received) >= 3, 5.0, spin=executor.spin_once)
    finally:
        code, out, err = finish(proc)
    assert code == 0, err
    assert [m.data for m in received] == ['hi'] * 3
    assert 'publishing #' not in out  # -p 0


def _stderr_when(proc, said, executor):
    """Spin until the process's stderr holds said (or TIMEOUT_S); stop it; its output."""
    err_lines = []

    def read():
        for line in proc.stderr:
            err_lines.append(line)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    wait_until(lambda: any(said in line for line in err_lines), TIMEOUT_S,
               spin=executor.spin_once)
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=TIMEOUT_S)
    finally:
        if proc.poll() is None:
            proc.kill()
    reader.join(5.0)
    return ''.join(err_lines)


def test_pub_of_another_type_than_the_subscribers_says_they_get_nothing(test_node):
    # DDS matches no subscription of another type and says nothing: the user would stream
    # Twist on /chassis_cmd and wonder why the chassis stays PASSIVE
    node, executor = test_node
    received = []
    node.create_subscription(ChassisCmd, '/cli_test/typed', received.append, 10)
    proc = rmcli('topic', 'pub', '-r', '20', '-p', '0', '/cli_test/typed',
                 'geometry_msgs/msg/Twist', '{linear: {x: 1.0}}')
    err = _stderr_when(proc, 'rmcli: warning:', executor)
    assert ('rmcli: warning: /cli_test/typed is subscribed as rm_msgs/msg/ChassisCmd '
            '(/test_cli_topic), not as geometry_msgs/msg/Twist: those subscribers never get '
            'these messages\n') in err, err
    assert err.count('rmcli: warning:') == 1, err  # once, not every period
    assert not received


def test_pub_whose_qos_no_subscriber_accepts_says_so(test_node):
    node, executor = test_node
    node.create_subscription(String, '/cli_test/reliable', lambda msg: None, 10)  # reliable
    proc = rmcli('topic', 'pub', '-r', '20', '-p', '0', '--qos-reliability', 'best_effort',
                 '/cli_test/reliable', 'std_msgs/msg/String', 'data: hi')
    err = _stderr_when(proc, 'rmcli: warning:', executor)
    assert ('rmcli: warning: /cli_test/reliable: QoS that no subscriber accepts '
            '(/test_cli_topic: Best effort publisher and reliable subscription): they never '
            'get these messages\n') in err, err


def test_pub_to_an_unknown_topic_without_type_is_one_clear_error():
    proc = rmcli('topic', 'pub', '--discovery-timeout', '0.5', '/cli_test/nobody', '{}')
    code, _, err = finish(proc)
    assert code == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and 'Traceback' not in err
    assert "topic '/cli_test/nobody' is not on the ROS graph" in lines[0]


def test_echo_once_prints_what_a_publisher_sends(test_node):
    node, executor = test_node
    publisher = node.create_publisher(ChassisCmd, '/cli_test/echo', 10)
    msg = ChassisCmd(mode=ChassisCmd.FOLLOW, follow_source='gimbal')
    msg.accel.linear.x = 1.25
    # Type from the graph; the wait for discovery ends as soon as the topic is seen.
    proc = rmcli('topic', 'echo', '--once', '--discovery-timeout', str(TIMEOUT_S), '/cli_test/echo')

    def publish_until_done():
        publisher.publish(msg)
        return proc.poll() is not None

    try:
        wait_until(publish_until_done, TIMEOUT_S, spin=executor.spin_once, period=0.05)
    finally:
        code, out, err = finish(proc)
    assert code == 0, err
    documents = out.split('---\n')
    assert len(documents) == 2 and documents[1] == ''  # exactly one message, then '---'
    echoed = yaml.safe_load(documents[0])
    assert echoed['mode'] == 2
    assert echoed['follow_source'] == 'gimbal'
    assert echoed['accel']['linear'] == {'x': 1.25, 'y': 0.0, 'z': 0.0}


def test_list_shows_topics_with_their_types(test_node):
    node, _ = test_node
    node.create_publisher(String, '/cli_test/listed', 10)
    # A new process can need one discovery announcement period (~3 s) to see this node;
    # list again instead of waiting the worst case every time.
    for _ in range(5):
        code, out, err = finish(rmcli('topic', 'list', '-t', '--spin-time', '1'))
        assert code == 0, err
        if '/cli_test/listed [std_msgs/msg/String]' in out.splitlines():
            break
    assert '/cli_test/listed [std_msgs/msg/String]' in out.splitlines()


def test_hz_reports_the_publishing_rate(test_node):
    node, executor = test_node
    publisher = node.create_publisher(String, '/cli_test/hz', 10)
    node.create_timer(0.05, lambda: publisher.publish(String(data='x')))  # 20 Hz
    proc = rmcli('topic', 'hz', '/cli_test/hz')
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
    reader.start()
    try:
        # ros2 topic hz prints about once a second; wait for two reports.
        wait_until(
            lambda: sum('average rate' in line for line in lines) >= 2,
            TIMEOUT_S,
            spin=executor.spin_once,
        )
    finally:
        proc.send_signal(signal.SIGINT)
        reader.join(timeout=TIMEOUT_S)
        proc.wait(timeout=TIMEOUT_S)
    rates = [float(line.split(':')[1]) for line in lines if line.startswith('average rate')]
    assert len(rates) >= 2, ''.join(lines) + proc.stderr.read()
    # 20 Hz from a timer in this process; the receiver sees some jitter, far less than this.
    assert 12.0 < rates[-1] < 28.0
    assert proc.returncode == 0


def test_bw_reports_the_message_sizes_and_a_rate(test_node):
    node, executor = test_node
    publisher = node.create_publisher(String, '/cli_test/bw', 10)
    # a 100-character string is 112 bytes serialised: 4 of CDR header, 4 of length, 101,
    # padded to 4
    node.create_timer(0.05, lambda: publisher.publish(String(data='x' * 100)))
    proc = rmcli('topic', 'bw', '/cli_test/bw')
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
    reader.start()
    try:
        wait_until(lambda: sum('Message size' in line for line in lines) >= 2, TIMEOUT_S,
                   spin=executor.spin_once)
    finally:
        proc.send_signal(signal.SIGINT)
        reader.join(timeout=TIMEOUT_S)
        proc.wait(timeout=TIMEOUT_S)
    assert lines[0] == 'Subscribed to [/cli_test/bw]\n', lines
    sizes = [line for line in lines if 'Message size' in line]
    assert sizes and sizes[-1] == '\tMessage size mean: 112 B min: 112 B max: 112 B\n', lines
    rates = [line for line in lines if '/s from ' in line]
    assert rates and float(rates[-1].split()[0]) > 0, lines
    assert proc.returncode == 0


def test_echo_ends_cleanly_on_sigint(test_node):
    node, executor = test_node
    proc = rmcli('topic', 'echo', '/cli_test/silent', 'std_msgs/msg/String')

    def subscribed():
        return any(name == '/cli_test/silent' for name, _ in node.get_topic_names_and_types())

    try:
        assert wait_until(subscribed, TIMEOUT_S, spin=executor.spin_once)
    finally:
        out, err = stop_process(proc)
    assert proc.returncode == 0, err
    assert (out, err) == ('', '')


def test_echo_once_with_timeout_fails_clearly_when_nothing_arrives():
    proc = rmcli(
        'topic', 'echo', '--once', '--timeout', '0.5', '/cli_test/quiet', 'std_msgs/msg/String'
    )
    code, out, err = finish(proc)
    assert code == 1
    assert out == ''
    assert err.strip() == "rmcli: error: no message on '/cli_test/quiet' within 0.5 s"
