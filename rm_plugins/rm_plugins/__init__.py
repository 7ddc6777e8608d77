"""rm_plugins: the robot mechanisms (chassis, gimbal, shooter, gpio, imu) as rm_base plugins."""
