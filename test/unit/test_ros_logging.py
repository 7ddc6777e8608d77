"""rm_base.ros_logging: rclpy's output, without rclpy's 400 µs caller lookup.

Each case runs a short script in a fresh interpreter (rcutils reads its output format
once per process) and compares its console lines, formatted as
``{severity} {name} {function_name}:{line_number} {message}``.
"""

import os
import subprocess
import sys
import textwrap

PRELUDE = """
import inspect, logging
from rclpy.logging import get_logger, LoggingSeverity
from rm_base.ros_logging import FastLogger, forward_package_logging

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
