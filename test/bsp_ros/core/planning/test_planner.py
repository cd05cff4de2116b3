"""The planner: within the limits, reversals in every joint, quasi-static, better than the paper's protocol."""

from __future__ import annotations

import numpy as np
from planning_cases import RANGES_DEG, SHOULDER_YZ_M, nominal_arm

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.planning import JointLimits, Plan, check_reachable, check_trajectory_within, predict_covariance


def test_plan_stays_within_the_ranges_and_speed(plan: Plan) -> None:
    check_trajectory_within(plan.trajectory, JointLimits(RANGES_DEG))
    check_reachable(plan.trajectory, nominal_arm().lengths_m, SHOULDER_YZ_M)
    assert max(plan.trajectory.peak_speed_rad_s) <= 0.03
    assert plan.trajectory.duration_s == 120.0


def test_plan_reverses_direction_in_every_joint(plan: Plan) -> None:
    t = np.arange(0.0, 120.0, 0.05)
    velocity = plan.trajectory.velocities_rad_s(t)
    for j in range(3):
        moving = velocity[np.abs(velocity[:, j]) > 0.005, j]
        reversals = int(np.count_nonzero(np.diff(np.sign(moving))))
        assert reversals >= 1, j
        assert min((moving > 0).mean(), (moving < 0).mean()) > 0.2, j


def test_plan_is_quasi_static(plan: Plan) -> None:
    assert np.all(plan.inertia_ratio < 0.01), plan.inertia_ratio
    assert np.all(plan.inertia_ratio > 0)


def test_plan_predicts_far_smaller_stds_than_the_paper_protocol(plan: Plan) -> None:
    paper = predict_covariance(
        sim.human_arm_cell().trajectory, 120.0, nominal_arm(), PassiveModel.parse("coulomb+offset+stiffness")
    )
    assert plan.prediction.max_relative_static_std < paper.max_relative_static_std / 10
    assert plan.prediction.std_of("offset_nm", "shoulder") < paper.std_of("offset_nm", "shoulder") / 10


def test_planning_is_deterministic(wrist_limited_plan: Plan) -> None:
    from bsp_ros.core.planning import plan_protocol

    again = plan_protocol(wrist_limited_plan.request)
    np.testing.assert_array_equal(again.trajectory.knots[1], wrist_limited_plan.trajectory.knots[1])


def test_a_two_segment_chain_is_planned_within_its_limits() -> None:
    from bsp_ros.core.planning import NominalArm, PlanRequest, plan_protocol

    limits = JointLimits(((-60.0, -15.0), (20.0, 80.0)))
    plan = plan_protocol(
        PlanRequest(
            nominal=NominalArm.from_anthropometry((0.3, 0.3)),
            shoulder_yz_m=SHOULDER_YZ_M,
            limits=limits,
            n_points=1,
            max_evaluations=60,
        )
    )
    assert plan.trajectory.n_joints == 2
    check_trajectory_within(plan.trajectory, limits)
    assert [name for name, _ in plan.prediction.names].count("offset_nm") == 2


def test_a_second_trunk_posture_is_predicted_as_a_second_recording_that_turns_gravity() -> None:
    trajectory, model = sim.human_arm_cell().trajectory, PassiveModel.parse("coulomb+offset+stiffness")
    one = predict_covariance(trajectory, 120.0, nominal_arm(), model)
    # The same posture twice: twice the information, half the covariance, twice the rows.
    twice = predict_covariance(trajectory, 120.0, nominal_arm(), model, trunk_tilts_rad=(0.0, 0.0))
    np.testing.assert_allclose(twice.covariance, one.covariance / 2, rtol=1e-9, atol=1e-18)
    assert twice.rows_used == {joint: 2 * rows for joint, rows in one.rows_used.items()}
    # Tilted by 25 deg, gravity turns relative to the arm and no longer trades with the shoulder's spring.
    tilted = predict_covariance(trajectory, 120.0, nominal_arm(), model, trunk_tilts_rad=(0.0, np.radians(25.0)))
    for quantity, owner in (("static_moment_kgm", "upper_arm"), ("offset_nm", "shoulder")):
        assert tilted.std_of(quantity, owner) < twice.std_of(quantity, owner) / 10, (quantity, owner)
