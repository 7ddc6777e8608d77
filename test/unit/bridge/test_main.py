"""Pieces of the can_bridge executable that run without ROS."""

import logging

import pytest
from rm_base.bridge.main import RosLogHandler


class FakeLogger:
    def __init__(self):
        self.lines = []

    def __getattr__(self, level):
        return lambda text: self.lines.append((level, text))


@pytest.mark.parametrize(
    ('level', 'method'),
    [
        (logging.ERROR, 'error'),
        (logging.WARNING, 'warning'),
        (logging.INFO, 'info'),
        (logging.DEBUG, 'debug'),
    ],
)
def test_python_log_records_reach_the_ros_logger_at_their_level(level, method):
    fake = FakeLogger()
    logger = logging.getLogger('rm_base.test_bridge_main')
    handler = RosLogHandler(fake)
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG)
    try:
        logger.log(level, 'wheel: output held at zero (%s)', 'offline')
    finally:
        logger.removeHandler(handler)
    assert fake.lines == [
        (method, 'rm_base.test_bridge_main: wheel: output held at zero (offline)')
    ]
