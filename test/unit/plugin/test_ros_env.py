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
