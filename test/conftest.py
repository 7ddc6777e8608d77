"""Session-wide test setup: ROS isolation before anything imports rclpy."""

import os

import pytest
from support.ros import isolate_ros_environment, rclpy_context

# Network rule: localhost-only discovery and a private domain, set before any test (or
# any process a test starts) can touch DDS; each pytest-xdist worker claims its own.
isolate_ros_environment(os.environ)


@pytest.fixture
def ros_context():
    """A private rclpy Context on the test domain, shut down after the test."""
    with rclpy_context() as context:
        yield context


@pytest.fixture(autouse=True)
def loop_lines_in_their_test():
    """Write what a control loop logged before the test ends (its thread writes later)."""
    yield
    from rm_base.ros_logging import flush_loop_lines  # imports rclpy: after the isolation

    flush_loop_lines()
