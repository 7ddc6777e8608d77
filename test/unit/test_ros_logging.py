"""rm_base.ros.log: rclpy's output, without rclpy's 400 µs caller lookup, and no line
written (nor sent on /rosout) by a control loop's thread.

The console cases run a short script in a fresh interpreter (rcutils reads its output
format once per process) and compare its console lines, formatted as
``{severity} {name} {function_name}:{line_number} {message}``.
"""

import os
import subprocess
import sys
import textwrap
import threading

from rm_base.ros.log import LogLine, LoopLines
from rm_base.runtime.realtime import loop_thread

PRELUDE = """
import inspect, logging
from rclpy.logging import get_logger, LoggingSeverity
from rm_base.ros.log import FastLogger, forward_package_logging

def no_source_lookup(*args, **kwargs):  # rclpy's slow caller lookup must not run
    raise AssertionError('inspect.getframeinfo called')

inspect.getframeinfo = no_source_lookup
"""


def console_lines(script: str) -> list[str]:
    env = dict(os.environ)
    env['RCUTILS_CONSOLE_OUTPUT_FORMAT'] = (
        '{severity} {name} {function_name}:{line_number} {message}')
    env['RCUTILS_COLORIZED_OUTPUT'] = '0'
    result = subprocess.run(
        [sys.executable, '-c', PRELUDE + textwrap.dedent(script)],
        env=env, capture_output=True, text=True, timeout=60, check=False,
    )
    assert result.returncode == 0, result.stderr
    return [line for line in (result.stdout + result.stderr).splitlines() if line]


def line_of(script: str, marker: str) -> int:
    """Line number of marker in script as run (after the prelude)."""
    lines = (PRELUDE + textwrap.dedent(script)).splitlines()
    return next(i for i, line in enumerate(lines, 1) if marker in line)


def test_when_logging_expect_rclpy_lines_with_the_callers_function_and_line():
    script = """
    def drive():
        log = FastLogger(get_logger('rm_robot')).get_child('chassis')
        log.info('PASSIVE -> RAW')  # here-info
        log.warning('wheel offline')  # here-warning
        log.debug('not shown at the default level')
        log.error('failed')  # here-error

    drive()
    """
    assert console_lines(script) == [
        f'INFO rm_robot.chassis drive:{line_of(script, "here-info")} PASSIVE -> RAW',
        f'WARN rm_robot.chassis drive:{line_of(script, "here-warning")} wheel offline',
        f'ERROR rm_robot.chassis drive:{line_of(script, "here-error")} failed',
    ]


def test_when_throttled_or_once_expect_one_line_per_call_site():
    script = """
    log = FastLogger(get_logger('can_bridge'))
    for i in range(50):
        log.warning(f'rejected {i}', throttle_duration_sec=60.0)
        log.info(f'first {i}', once=True)
        log.info(f'every {i}') if i < 2 else None
    """
    assert [line.split(' ', 3)[3] for line in console_lines(script)] == [
        'rejected 0', 'first 0', 'every 0', 'every 1',
    ]


def test_when_the_throttle_period_passed_expect_the_next_line():
    script = """
    import time
    log = FastLogger(get_logger('can_bridge'))
    for i in range(3):
        log.warning(f'rejected {i}', throttle_duration_sec=0.05)
        time.sleep(0.1)
    """
    assert [line.split(' ', 3)[3] for line in console_lines(script)] == [
        'rejected 0', 'rejected 1', 'rejected 2',
    ]


def test_when_the_level_is_raised_expect_lower_lines_dropped():
    script = """
    log = FastLogger(get_logger('rm_robot'))
    log.set_level(LoggingSeverity.WARN)
    log.info('dropped')
    log.warning('kept')
    """
    assert [line.split(' ', 3)[3] for line in console_lines(script)] == ['kept']


def test_when_python_logging_records_are_forwarded_expect_them_at_their_level_and_caller():
    script = """
    forward_package_logging('can_bridge')
    hw = logging.getLogger('rm_base.hardware.actuators')

    def hold():
        hw.info('wheel: output held at zero (%s)', 'offline')  # here-info
        hw.warning('can0: bus off')  # here-warning
        hw.critical('gone')  # here-critical
        hw.debug('not forwarded')

    hold()
    logging.getLogger('other').warning('not ours: lastResort, plain')
    """
    assert console_lines(script) == [
        f'INFO can_bridge hold:{line_of(script, "here-info")} '
        'rm_base.hardware.actuators: wheel: output held at zero (offline)',
        f'WARN can_bridge hold:{line_of(script, "here-warning")} '
        'rm_base.hardware.actuators: can0: bus off',
        f'FATAL can_bridge hold:{line_of(script, "here-critical")} '
        'rm_base.hardware.actuators: gone',
        'not ours: lastResort, plain',
    ]


def test_when_a_loop_thread_logs_expect_its_lines_written_in_order_before_later_lines():
    script = """
    import threading
    from rm_base.runtime.realtime import loop_thread

    log = FastLogger(get_logger('rm_robot')).get_child('chassis')

    def loop():
        with loop_thread():
            for i in range(3):
                log.info(f'tick {i}')
            forward_package_logging('rm_robot')
            logging.getLogger('rm_base.hardware').warning('held at zero')

    worker = threading.Thread(target=loop)
    worker.start()
    worker.join()
    log.info('after the loop')
    with loop_thread():
        log.error('queued last: written at exit')
    """
    assert [line.split(' ', 3)[3] for line in console_lines(script)] == [
        'tick 0', 'tick 1', 'tick 2', 'rm_base.hardware: held at zero', 'after the loop',
        'queued last: written at exit',
    ]


def test_when_logging_expect_the_line_on_rosout_with_its_caller():
    script = """
    import threading, time
    import rclpy
    from rcl_interfaces.msg import Log
    from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy
    from rm_base.runtime.realtime import loop_thread

    rclpy.init()
    node = rclpy.create_node('rosout_probe')
    got = []
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(Log, '/rosout', got.append, qos)
    log = FastLogger(node.get_logger()).get_child('kid')

    def loop():
        with loop_thread():
            log.warning('from the loop')  # here-loop

    log.info('from main')  # here-main
    worker = threading.Thread(target=loop)
    worker.start()
    worker.join()
    deadline = time.monotonic() + 20.0
    while len(got) < 2 and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.1)
    for m in got:
        print('ROSOUT', m.level, m.name, m.function, m.line, m.msg, m.file.endswith('<string>'))
    """
    rosout = [line for line in console_lines(script) if line.startswith('ROSOUT')]
    assert rosout == [
        f'ROSOUT 20 rosout_probe.kid <module> {line_of(script, "here-main")} from main True',
        f'ROSOUT 30 rosout_probe.kid loop {line_of(script, "here-loop")} from the loop True',
    ]


class BlockingWriter:
    """A LoopLines ``write`` that records each line's thread and holds the first one."""

    def __init__(self):
        self.lines = []
        self.entered = threading.Event()
        self.release = threading.Event()

    def __call__(self, line):
        self.lines.append((threading.current_thread().name, line.name, line.message))
        self.entered.set()
        assert self.release.wait(10.0)


def test_a_loop_threads_line_never_waits_for_the_write():
    writer = BlockingWriter()
    lines = LoopLines(write=writer)
    try:
        with loop_thread():
            lines.put(LogLine(20, 'rm_robot', 'first', 'f', 'p', 1))
            assert writer.entered.wait(10.0)  # the write of 'first' now blocks
            for i in range(50):
                lines.put(LogLine(20, 'rm_robot', f'then {i}', 'f', 'p', 1))
        assert [t for t, _, _ in writer.lines] == ['rm-log']
    finally:
        writer.release.set()
        lines.flush()
    assert [m for _, _, m in writer.lines] == ['first'] + [f'then {i}' for i in range(50)]


def test_when_more_lines_wait_than_the_queue_holds_expect_the_oldest_dropped_and_reported():
    writer = BlockingWriter()
    lines = LoopLines(max_lines=3, write=writer)
    lines.put(LogLine(20, 'rm_robot.gimbal', 'first', 'f', 'p', 1))
    assert writer.entered.wait(10.0)
    for i in range(5):
        lines.put(LogLine(20, 'rm_robot.chassis', f'line {i}', 'f', 'p', 1))
    writer.release.set()
    lines.write(LogLine(20, 'rm_robot', 'last', 'f', 'p', 1))
    assert [(n, m) for _, n, m in writer.lines] == [
        ('rm_robot.gimbal', 'first'),
        ('rm_robot.chassis', '2 log line(s) of the control loop dropped: more than 3 waited '
                             'to be written'),
        ('rm_robot.chassis', 'line 2'), ('rm_robot.chassis', 'line 3'),
        ('rm_robot.chassis', 'line 4'), ('rm_robot', 'last'),
    ]
    assert lines.dropped == 2


def test_outside_a_loop_thread_a_line_is_written_in_the_callers_thread():
    writer = BlockingWriter()
    writer.release.set()
    lines = LoopLines(write=writer)
    lines.write(LogLine(20, 'rm_robot', 'now', 'f', 'p', 1))
    assert writer.lines == [(threading.current_thread().name, 'rm_robot', 'now')]



def test_while_held_a_loop_threads_lines_wait_until_release():
    writer = BlockingWriter()
    writer.release.set()
    lines = LoopLines(write=writer)
    with loop_thread():
        lines.put(LogLine(20, 'rm_robot', 'before', 'f', 'p', 1))
        lines.hold()  # writes what is queued, here if the thread has not yet
        assert [m for _, _, m in writer.lines] == ['before']
        writer.entered.clear()
        lines.put(LogLine(20, 'rm_robot', 'held', 'f', 'p', 1))  # wakes the writing thread
        assert not writer.entered.wait(0.2)
    lines.release()
    assert writer.entered.wait(10.0)
    assert writer.lines[1] == ('rm-log', 'rm_robot', 'held')


def test_while_held_another_threads_line_comes_after_the_held_ones():
    writer = BlockingWriter()
    writer.release.set()
    lines = LoopLines(write=writer)
    lines.hold()
    with loop_thread():
        lines.put(LogLine(20, 'rm_robot', 'held', 'f', 'p', 1))
    lines.write(LogLine(20, 'rm_robot', 'now', 'f', 'p', 1))
    assert [m for _, _, m in writer.lines] == ['held', 'now']
    lines.release()
