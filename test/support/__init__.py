"""Shared helpers for the rm_ros2 test suite."""
