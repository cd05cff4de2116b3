"""The middleware layer: rclpy (ROS 2 Jazzy), message classes by name, QoS profiles, parameters, spin."""
