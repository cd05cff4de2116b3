"""bsp_ros: body segment parameters and passive joint moments of the arm, identified online."""

__version__ = "0.1.0"
