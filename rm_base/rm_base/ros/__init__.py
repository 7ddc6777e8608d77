"""The ROS edge: taking and publishing messages, log lines, the process's ROS set-up."""
