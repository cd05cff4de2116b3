"""Online building blocks: causal joint angles, windowed and recursive identification (no clocks, no ROS)."""
