"""rm_base.ros.env: localhost discovery by default, SIGTERM handled like SIGINT. No ROS."""

import os
import signal

import pytest
from rm_base.ros.env import (
    init_error_line,
    params_file_error,
    prepare_ros_process,
    use_localhost_discovery,
)


def test_when_unset_expect_localhost():
    environ = {}
    assert use_localhost_discovery(environ) == 'LOCALHOST'
    assert environ == {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}


def test_a_choice_of_the_user_is_kept():
    environ = {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}
    assert use_localhost_discovery(environ) == 'SUBNET'


def test_after_prepare_sigterm_raises_keyboard_interrupt():
    saved = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    try:
        prepare_ros_process({})
        with pytest.raises(KeyboardInterrupt, match='SIGTERM'):
            os.kill(os.getpid(), signal.SIGTERM)
            signal.sigtimedwait([], 1.0)  # give the handler a chance to run
    finally:
        signal.signal(signal.SIGINT, saved[0])
        signal.signal(signal.SIGTERM, saved[1])


def test_init_error_line_keeps_rcl_message_without_source_locations():
    err = RuntimeError(
        "failed to initialize rcl: Couldn't parse params file: '--params-file r.yaml'. "
        'Error: Will not support aliasing at line 33\n, at /project/src/parse.c:893, at '
        '/project/src/rcl/arguments.c:415'
    )
    assert init_error_line(err) == (
        "failed to initialize rcl: Couldn't parse params file: '--params-file r.yaml'. "
        'Error: Will not support aliasing at line 33'
    )


def test_params_file_error_accepts_a_valid_file(tmp_path):
    path = tmp_path / 'ok.yaml'
    path.write_text('node:\n  ros__parameters:\n    a: 1\n')
    assert params_file_error(['x', '--ros-args', '--params-file', str(path)]) is None


def test_params_file_error_names_the_place_of_broken_yaml(tmp_path):
    path = tmp_path / 'broken.yaml'
    path.write_text('node:\n  ros__parameters:\n    a: {b: 1\n')
    line = params_file_error(['--params-file', str(path)])
    assert line.startswith(f'{path}:4:1: not valid YAML: '), line


def test_params_file_error_rejects_anchors_as_rcl_does(tmp_path):
    path = tmp_path / 'anchors.yaml'
    path.write_text('node:\n  ros__parameters:\n    a: &v 1\n    b: *v\n')
    assert params_file_error(['--params-file', str(path)]).startswith(f'{path}:4: YAML anchors')


def test_params_file_error_names_a_missing_file(tmp_path):
    line = params_file_error(['--params-file', str(tmp_path / 'nope.yaml')])
    assert line.startswith('cannot read parameter file') and 'nope.yaml' in line


_TEARDOWN_CHILD = """
import ctypes, sys
from rm_base.ros.env import bounded_teardown
with bounded_teardown(float(sys.argv[1])):
    # a C call that keeps the interpreter lock, as Fast DDS's stuck destroy does
    ctypes.PyDLL(None).usleep(int(float(sys.argv[2]) * 1e6))
print('torn down', flush=True)
"""


@pytest.mark.parametrize(
    ('timeout_s', 'teardown_s', 'code', 'out', 'err'),
    [
        (5.0, 0.1, 0, 'torn down\n', ''),  # in time: nothing said, nothing cut short
        (0.3, 20.0, 1, '', 'Timeout (0:00:00.300000)!'),  # stuck: out within its bound
    ],
)
def test_a_teardown_that_hangs_ends_the_process_with_its_stacks(
    timeout_s, teardown_s, code, out, err
):
    import subprocess
    import sys
    import time

    started = time.monotonic()
    child = subprocess.run(
        [sys.executable, '-c', _TEARDOWN_CHILD, str(timeout_s), str(teardown_s)],
        capture_output=True, text=True, timeout=60, check=False,
    )
    assert (child.returncode, child.stdout) == (code, out), child.stderr
    assert err in child.stderr
    assert time.monotonic() - started < 15.0  # not the 20 s of the stuck call
