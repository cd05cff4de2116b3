"""The pure core (numpy/scipy only: no ROS, no bags, no clocks): model, angles, identification, priors, simulation."""
