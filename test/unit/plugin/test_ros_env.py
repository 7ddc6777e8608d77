"""rm_base.ros_env: localhost discovery by default, SIGTERM handled like SIGINT. No ROS."""

import os
import signal

import pytest
from rm_base.ros_env import prepare_ros_process, use_localhost_discovery


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
