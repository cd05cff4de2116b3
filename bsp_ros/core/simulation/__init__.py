"""A simulated rehab cell: a planar arm moved by a robot, with noisy wrench (fixed or turning sensor) and markers.

Modules: ``subject`` (the arm's truth), ``trajectory`` (the motion), ``sensor`` and ``markers`` (the
streams), ``cell`` (a session's spec), ``dynamics`` (Newton-Euler inverse dynamics), ``truth`` (the truth
file), ``simulator`` (the cell), ``tare`` (handle-free recordings).
"""

from bsp_ros.core.simulation.cell import CellSpec, human_arm_cell, paper_mechanical_arm_cell
from bsp_ros.core.simulation.checks import DEFAULT_START_NS, GRAVITY_M_S2, TRUTH_SCHEMA, rotation_from_rpy_deg
from bsp_ros.core.simulation.dynamics import PlanarChain, inverse_dynamics_nm
from bsp_ros.core.simulation.markers import MarkerSpec, skin_offsets_m
from bsp_ros.core.simulation.sensor import FILTER_KINDS, SensorSpec
from bsp_ros.core.simulation.simulator import CellSimulator, SimulatedSession, simulate_cell
from bsp_ros.core.simulation.subject import PAPER_ARM_INERTIA_ASSUMPTION, PassiveTruth, SubjectTruth
from bsp_ros.core.simulation.tare import SimulatedTare, TareSpec, simulate_tare, tare_rotations
from bsp_ros.core.simulation.trajectory import (
    JointTrajectory,
    MultiSineTrajectory,
    TrajectorySpec,
    TrunkTiltedTrajectory,
    joint_accelerations_rad_s2,
)
from bsp_ros.core.simulation.truth import SessionTruth

__all__ = [
    "DEFAULT_START_NS",
    "FILTER_KINDS",
    "GRAVITY_M_S2",
    "PAPER_ARM_INERTIA_ASSUMPTION",
    "TRUTH_SCHEMA",
    "CellSimulator",
    "CellSpec",
    "JointTrajectory",
    "MarkerSpec",
    "MultiSineTrajectory",
    "PassiveTruth",
    "PlanarChain",
    "SensorSpec",
    "SessionTruth",
    "SimulatedSession",
    "SimulatedTare",
    "SubjectTruth",
    "TareSpec",
    "TrajectorySpec",
    "TrunkTiltedTrajectory",
    "human_arm_cell",
    "inverse_dynamics_nm",
    "joint_accelerations_rad_s2",
    "paper_mechanical_arm_cell",
    "rotation_from_rpy_deg",
    "simulate_cell",
    "simulate_tare",
    "skin_offsets_m",
    "tare_rotations",
]
