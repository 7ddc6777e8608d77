"""The referee system on the robot: its records as rm_msgs messages (``messages``)."""
