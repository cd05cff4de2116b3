"""ROS messages <-> numpy: attribute access only, so rclpy and rosbags messages both work."""
