"""rm_base: the rm_ros2 framework (plugins, host, control maths, CAN layer, bridge, simulator)."""
