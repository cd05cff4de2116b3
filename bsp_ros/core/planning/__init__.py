"""Protocol planning: robot trajectories that make every reported parameter identifiable."""

from bsp_ros.core.planning.budget import PredictedBudget, SessionSpec, predict_budget
from bsp_ros.core.planning.compare import compare_budget_with_estimate, compare_with_result, compare_with_scatter
from bsp_ros.core.planning.files import (
    PLAN_SCHEMA,
    plan_to_dict,
    planned_trajectory_from_file,
    write_plan_csv,
    write_plan_json,
)
from bsp_ros.core.planning.inertia import plan_inertia_protocol, simulated_inertia_std
from bsp_ros.core.planning.information import NoiseSpec, NominalArm, Prediction, predict_covariance
from bsp_ros.core.planning.planner import InfeasiblePlanError, Plan, PlanRequest, plan_protocol, trajectory_from_points
from bsp_ros.core.planning.safety import (
    JointLimits,
    check_reachable,
    check_trajectory_within,
    joint_angles_from_handle_poses,
)
from bsp_ros.core.planning.trajectory import PlannedTrajectory, handle_poses_world

__all__ = [
    "PLAN_SCHEMA",
    "InfeasiblePlanError",
    "JointLimits",
    "NoiseSpec",
    "NominalArm",
    "Plan",
    "PlanRequest",
    "PlannedTrajectory",
    "PredictedBudget",
    "Prediction",
    "SessionSpec",
    "check_reachable",
    "check_trajectory_within",
    "compare_budget_with_estimate",
    "compare_with_result",
    "compare_with_scatter",
    "handle_poses_world",
    "joint_angles_from_handle_poses",
    "plan_inertia_protocol",
    "plan_protocol",
    "plan_to_dict",
    "planned_trajectory_from_file",
    "predict_budget",
    "predict_covariance",
    "simulated_inertia_std",
    "trajectory_from_points",
    "write_plan_csv",
    "write_plan_json",
]
