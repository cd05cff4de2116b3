"""Live: the online building blocks, the thin rclpy layer, the nodes, and play/record of bags on ROS 2 topics."""
