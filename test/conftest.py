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


@pytest.fixture
def test_node(ros_context, request):
    """A node of the test's own (named after its module) and an executor to spin it."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    node = rclpy.create_node(request.module.__name__.rpartition('.')[2], context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    yield node, executor
    executor.shutdown()
    node.destroy_node()


def _loop_lines_within(phase):
    """Run a test phase with the control loops' lines written only while it runs.

    A loop's lines are written by a thread of their own (rm_base.ros.log); pytest
    captures output only during a phase, so a line written while pytest reports between
    phases reached the terminal. trylast: inside pytest's own capture wrapper.
    """

    @pytest.hookimpl(wrapper=True, trylast=True)
    def hook(item):
        from rm_base.ros.log import hold_loop_lines, release_loop_lines  # after isolation

        release_loop_lines()
        try:
            return (yield)
        finally:
            hold_loop_lines()

    hook.__name__ = f'pytest_runtest_{phase}'
    return hook


pytest_runtest_setup = _loop_lines_within('setup')
pytest_runtest_call = _loop_lines_within('call')
pytest_runtest_teardown = _loop_lines_within('teardown')


def pytest_sessionfinish(session):
    from rm_base.ros.log import release_loop_lines

    release_loop_lines()
